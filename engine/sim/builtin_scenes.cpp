#include "sim/builtin_scenes.h"

#include <algorithm>
#include <stdexcept>

#include "sim/gltf_scene.h"
#include "sim/textures.h"

namespace evflow::sim {

namespace {

// The room of the built-in scenes; `textures` fills its seven material slots: back-wall poster,
// floor, right wall, noise boxes, grating, dark (left wall and a box), sign.
Scene make_room(const std::string& source, std::vector<Texture> textures) {
  Scene s;
  s.source = source;
  s.textures = std::move(textures);
  auto mat = [&](const char* name, int tex, std::array<float, 4> f = {1, 1, 1, 1}) {
    s.materials.push_back(Material{name, f, tex});
    return uint32_t(s.materials.size() - 1);
  };
  const uint32_t m_text = mat("poster", 0), m_floor = mat("floor", 1), m_brick = mat("brick", 2),
                 m_noise = mat("noise", 3), m_grating = mat("grating", 4), m_dark = mat("dark", 5),
                 m_sign = mat("sign", 6), m_white = mat("white", 0, {1.1f, 1.1f, 1.1f, 1});
  // Room: floor, back wall, left (dark) and right (brick) walls; open top and front.
  s.add_quad({-4, -1, 3}, {4, -1, 3}, {4, -1, -4}, {-4, -1, -4}, m_floor, 4, 3.5f);
  s.add_quad({-4, -1, -4}, {4, -1, -4}, {4, 3, -4}, {-4, 3, -4}, m_text, 2, 1);
  s.add_quad({-4, -1, 3}, {-4, -1, -4}, {-4, 3, -4}, {-4, 3, 3}, m_dark, 3.5f, 2);
  s.add_quad({4, -1, -4}, {4, -1, 3}, {4, 3, 3}, {4, 3, -4}, m_brick, 3.5f, 2);
  // Objects at several depths.
  s.add_box({-2.4f, -1, -2.8f}, {-1.0f, 0.5f, -1.6f}, m_noise, 0.7f);
  s.add_box({0.6f, -1, -3.2f}, {2.3f, 1.3f, -2.4f}, m_white, 0.5f);
  s.add_box({-0.5f, -1, -0.6f}, {0.5f, -0.25f, 0.3f}, m_grating, 1.0f);
  s.add_box({2.0f, -1, -0.8f}, {2.9f, 0.1f, 0.2f}, m_dark, 1.0f);
  s.add_box({-1.8f, -1, 0.6f}, {-1.2f, -0.6f, 1.2f}, m_noise, 1.5f);
  // Posters: a grating on the left wall, a bright-on-dark sign above the white box.
  s.add_quad({-3.98f, -0.2f, -2.5f}, {-3.98f, -0.2f, -0.5f}, {-3.98f, 1.6f, -0.5f}, {-3.98f, 1.6f, -2.5f}, m_grating);
  s.add_quad({0.4f, 1.6f, -3.97f}, {2.6f, 1.6f, -3.97f}, {2.6f, 2.6f, -3.97f}, {0.4f, 2.6f, -3.97f}, m_sign, 1, 0.45f);
  s.has_view_hint = true;
  s.view_target = {0, 0, -1.5f};
  s.view_radius = 5.0f;
  s.view_height = 1.0f;
  s.validate();
  return s;
}

// Three boxes (coarse checks, coarse bricks, one flat colour) on plain, untextured floor and walls:
// large smooth regions that a model can fit almost exactly, so reconstructions here can go well
// past the room scenes' scores.
Scene make_objects_scene() {
  Scene s;
  s.source = "objects";
  s.textures = {checker_texture(), brick_texture()};
  auto mat = [&](const char* name, int tex, std::array<float, 4> f) {
    s.materials.push_back(Material{name, f, tex});
    return uint32_t(s.materials.size() - 1);
  };
  const uint32_t m_floor = mat("floor", -1, {0.32f, 0.3f, 0.28f, 1}),
                 m_back = mat("backdrop", -1, {0.55f, 0.52f, 0.46f, 1}),
                 m_side = mat("side", -1, {0.4f, 0.43f, 0.48f, 1}), m_checker = mat("checker", 0, {1, 1, 1, 1}),
                 m_brick = mat("brick", 1, {1, 1, 1, 1}), m_blue = mat("blue", -1, {0.12f, 0.2f, 0.5f, 1});
  s.add_quad({-4, -1, 3}, {4, -1, 3}, {4, -1, -4}, {-4, -1, -4}, m_floor);
  s.add_quad({-4, -1, -4}, {4, -1, -4}, {4, 3, -4}, {-4, 3, -4}, m_back);
  s.add_quad({-4, -1, 3}, {-4, -1, -4}, {-4, 3, -4}, {-4, 3, 3}, m_side);
  s.add_quad({4, -1, -4}, {4, -1, 3}, {4, 3, 3}, {4, 3, -4}, m_side);
  s.add_box({-2.2f, -1, -2.2f}, {-0.9f, 0.3f, -0.9f}, m_checker, 0.25f);
  s.add_box({0.5f, -1, -2.8f}, {2.0f, 0.8f, -2.0f}, m_brick, 0.2f);
  s.add_box({-0.3f, -1, -0.4f}, {0.6f, -0.3f, 0.5f}, m_blue);
  s.has_view_hint = true;
  s.view_target = {0, -0.3f, -1.2f};
  s.view_radius = 4.5f;
  s.view_height = 1.2f;
  s.validate();
  return s;
}

}  // namespace

Scene make_default_scene() {
  return make_room("default",
                   {text_texture(1, 0.85, 0.03, {1.0, 0.97, 0.9}), checker_texture(), brick_texture(), noise_texture(3),
                    grating_texture(), dark_texture(), text_texture(2, 0.04, 0.9, {1.0, 0.85, 0.5})});
}

std::vector<std::string> builtin_scene_names() { return {"default", "gallery", "workshop", "objects"}; }

double builtin_scene_blur_px(const std::string& name) {
  if (name == "default") return 6;
  if (name == "gallery") return 4;
  if (name == "workshop") return 9;
  if (name == "objects") return 8;
  throw std::invalid_argument("no built-in scene '" + name + "'");
}

Scene make_builtin_scene(const std::string& name) {
  if (name == "default") return make_default_scene();
  // Same room, other surfaces: fine print everywhere and bright noise (high-frequency texture).
  if (name == "gallery")
    return make_room("gallery", {text_texture(11, 0.9, 0.05, {0.95, 0.95, 1.0}), noise_texture(17),
                                 text_texture(12, 0.1, 0.95, {0.7, 1.0, 0.8}), brick_texture(),
                                 text_texture(13, 0.8, 0.1, {1.0, 0.9, 0.8}), noise_texture(23), grating_texture()});
  // Same room, other surfaces: large smooth shapes, coarse bricks and gratings, dark corners.
  if (name == "workshop")
    return make_room("workshop", {brick_texture(), grating_texture(), checker_texture(), dark_texture(),
                                  checker_texture(), brick_texture(), noise_texture(31)});
  if (name == "objects") return make_objects_scene();
  throw std::invalid_argument("unknown built-in scene '" + name + "' (default, gallery, workshop, objects)");
}

Scene builtin_or_gltf_scene(const std::string& name_or_path) {
  if (name_or_path.empty()) return make_default_scene();
  const std::vector<std::string> names = builtin_scene_names();
  if (std::find(names.begin(), names.end(), name_or_path) != names.end()) return make_builtin_scene(name_or_path);
  return load_gltf(name_or_path);
}

}  // namespace evflow::sim
