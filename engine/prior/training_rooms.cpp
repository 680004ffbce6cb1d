#include "prior/training_rooms.h"

#include <array>
#include <random>
#include <string>

#include "sim/textures.h"

namespace evflow::prior {

namespace {

// Six textures of the room's own seeds, and a material per surface drawing one with a tint.
struct RoomMaterials {
  RoomMaterials(sim::Scene& scene, std::mt19937_64& rng, uint64_t seed) : s(scene), g(rng) {
    const uint32_t base = uint32_t(1000 + 16 * (seed % 100000));
    s.textures = {sim::text_texture(base + 1, uniform(0.5, 0.95), uniform(0.02, 0.2), {1.0, 0.95, 0.9}),
                  sim::noise_texture(base + 2),
                  sim::checker_texture(),
                  sim::brick_texture(),
                  sim::grating_texture(),
                  sim::dark_texture(),
                  sim::text_texture(base + 3, uniform(0.02, 0.2), uniform(0.6, 0.95), {0.9, 0.95, 1.0})};
  }
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }
  uint32_t next(const std::string& name) {
    const int tex = int(std::uniform_int_distribution<size_t>(0, s.textures.size())(g)) - 1;  // -1: plain
    const float gain = float(uniform(0.5, 1.3));
    std::array<float, 4> tint{gain * float(uniform(0.6, 1.0)), gain * float(uniform(0.6, 1.0)),
                              gain * float(uniform(0.6, 1.0)), 1.0f};
    s.materials.push_back(sim::Material{name + std::to_string(s.materials.size()), tint, tex});
    return uint32_t(s.materials.size() - 1);
  }
  sim::Scene& s;
  std::mt19937_64& g;
};

}  // namespace

sim::Scene make_training_room(uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 0x5EED);
  sim::Scene s;
  s.source = "prior-room-" + std::to_string(seed);
  RoomMaterials m(s, rng, seed);
  const float w = float(m.uniform(3, 5)), d = float(m.uniform(3.5, 5)), h = float(m.uniform(2.5, 4));
  auto tile = [&] { return float(m.uniform(1, 4)); };
  s.add_quad({-w, -1, 3}, {w, -1, 3}, {w, -1, -d}, {-w, -1, -d}, m.next("floor"), tile(), tile());
  s.add_quad({-w, -1, -d}, {w, -1, -d}, {w, h, -d}, {-w, h, -d}, m.next("back"), tile(), tile());
  s.add_quad({-w, -1, 3}, {-w, -1, -d}, {-w, h, -d}, {-w, h, 3}, m.next("left"), tile(), tile());
  s.add_quad({w, -1, -d}, {w, -1, 3}, {w, h, 3}, {w, h, -d}, m.next("right"), tile(), tile());
  const int boxes = int(m.uniform(3, 7));
  for (int b = 0; b < boxes; ++b) {
    const float cx = float(m.uniform(-w + 1, w - 1)), cz = float(m.uniform(-d + 0.8, 1.0));
    const float sx = float(m.uniform(0.25, 0.9)), sz = float(m.uniform(0.25, 0.9)), top = float(m.uniform(-0.5, 1.5));
    s.add_box({cx - sx, -1, cz - sz}, {cx + sx, top, cz + sz}, m.next("box"), float(m.uniform(0.3, 1.5)));
  }
  s.has_view_hint = true;
  s.view_target = {float(m.uniform(-0.5, 0.5)), float(m.uniform(-0.5, 0.3)), float(m.uniform(-2, -1))};
  s.view_radius = float(m.uniform(4.5, 5.5));
  s.view_height = float(m.uniform(0.6, 1.4));
  s.validate();
  return s;
}

}  // namespace evflow::prior
