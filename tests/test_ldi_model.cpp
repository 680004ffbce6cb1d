// The learnable double integral (engine/ldi/ldi_model.h): the frames and double integrals
// against the double-precision reference (tests/reference/ldi_reference.h), the network's weight
// gradients of both backward modes (and of the frames with the anchor) against central differences of that reference,
// the neutral initialisation, the checks on bad input, and the whole-view evaluation in tiles (full_view.h).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "events/gpu_events.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "ldi/full_view.h"
#include "ldi/ldi_model.h"
#include "reference/ldi_reference.h"

using namespace evflow;

namespace {

std::vector<double> uniform(size_t n, std::mt19937& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(n);
  for (double& x : v) x = double(float(u(rng)));  // exactly what the GPU sees
  return v;
}

std::vector<float> to_float(const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); }

void require_close(const std::vector<float>& got, const std::vector<double>& want, double tol, const char* what) {
  REQUIRE(got.size() >= want.size());
  double scale = 1e-6;
  for (double w : want) scale = std::max(scale, std::abs(w));
  for (size_t i = 0; i < want.size(); ++i) {
    INFO(what << " [" << i << "]: " << got[i] << " vs " << want[i] << " (largest " << scale << ")");
    REQUIRE(std::abs(double(got[i]) - want[i]) <= tol * (std::abs(want[i]) + 0.05 * scale));
  }
}

struct Case {
  EventStream stream;
  std::vector<ref::LdiEvent> events;
  ref::LdiNet net;
  ref::LdiCrop crop{2, 1, 5, 4};
  std::vector<double> times{0.0, 0.37, 1.0};  // t_0, inside, t_2N
  ref::NnTensor blurry{3, 4, 5};
};

Case make_case() {
  Case c;
  std::mt19937 rng(7);
  c.stream.width = 8, c.stream.height = 6;
  std::vector<double> t = uniform(400, rng, 0.0, 1.0);
  std::sort(t.begin(), t.end());
  for (double ti : t) {
    const auto x = uint16_t(rng() % 8), y = uint16_t(rng() % 6);
    const int8_t p = rng() % 3 ? 1 : -1;
    c.stream.push(x, y, ti, p);
    c.events.push_back({ti, x, y, p});
  }
  c.net.widths = {32, 4, 3, 1};
  for (size_t i = 0; i + 1 < c.net.widths.size(); ++i) {
    c.net.weight.push_back(uniform(size_t(c.net.widths[i]) * c.net.widths[i + 1] * 9, rng, -0.25, 0.25));
    c.net.bias.push_back(uniform(c.net.widths[i + 1], rng, -0.2, 0.4));
  }
  c.blurry.v = uniform(c.blurry.v.size(), rng, 0.1, 0.9);
  return c;
}

void set_weights(ldi::LdiModel& m, const ref::LdiNet& net) {
  for (size_t i = 0; i + 1 < net.widths.size(); ++i)
    m.network().layer(i).set_parameters(to_float(net.weight[i]), to_float(net.bias[i]));
}

std::vector<double> flatten(const std::vector<ref::NnTensor>& ts) {
  std::vector<double> v;
  for (auto& t : ts) v.insert(v.end(), t.v.begin(), t.v.end());
  return v;
}

// `frames` buffers of `values` values each, consecutive parts of r.
std::vector<gpu::Buffer> frame_grads(gpu::Context& ctx, const std::vector<double>& r, uint32_t frames, size_t values) {
  std::vector<gpu::Buffer> grads;
  for (uint32_t i = 0; i < frames; ++i) {
    grads.emplace_back(ctx, values * 4, "frame_grad");
    grads.back().write(to_float(std::vector<double>(r.begin() + i * values, r.begin() + (i + 1) * values)));
  }
  return grads;
}

// Every layer's weight and bias gradients against central differences of `loss`, which reads `net`.
void require_weight_grads(ldi::LdiModel& model, ref::LdiNet& net, const std::function<double()>& loss) {
  for (size_t l = 0; l + 1 < net.widths.size(); ++l) {
    INFO("layer " << l);
    nn::Conv2d& conv = model.network().layer(l);
    require_close(conv.weight_grad().read<float>(net.weight[l].size()),
                  ref::nn_central_differences(net.weight[l], loss, 1e-5), 2e-3, "dW");
    require_close(conv.bias_grad().read<float>(net.bias[l].size()),
                  ref::nn_central_differences(net.bias[l], loss, 1e-5), 2e-3, "db");
  }
}

}  // namespace

TEST_CASE("LDI: frames against the double reference, weight gradients against central differences", "[ldi][gpu]") {
  auto& ctx = test::gpu_context();
  Case c = make_case();
  GpuEvents events(ctx, c.stream, {{0.0, 1.0}}, "random events");
  // The 4 calls (t_0 and t_2N have one side each) as one batch, one call at a time, and in a
  // chunk of 3 and one of 1 (the backward runs the first chunk's forward again).
  const uint32_t max_batch = GENERATE(0u, 1u, 3u);
  INFO("calls per chunk at most " << max_batch);
  ldi::LdiModel model(ctx, events, c.net.widths, c.crop.w, c.crop.h, 3, max_batch);
  CHECK(model.batch() == (max_batch ? max_batch : 6u));
  set_weights(model, c.net);
  gpu::Buffer blurry(ctx, c.blurry.v.size() * 4, "blurry_crop");
  blurry.write(to_float(c.blurry.v));
  gpu::Commands cmd(ctx);
  const ldi::Crop crop{c.crop.x, c.crop.y, c.crop.w, c.crop.h};
  model.forward(cmd, 0, c.times, crop, blurry);
  cmd.submit();
  const ref::LdiFrames want = ref::ldi_frames(c.net, c.events, 0.0, 1.0, c.times, c.crop, c.blurry);
  require_close(model.integral().read<float>(3 * 20), flatten(want.integral), 1e-5, "E");
  std::vector<float> frames;
  for (uint32_t i = 0; i < 3; ++i) {
    const auto f = model.frame(i).read<float>(60);
    frames.insert(frames.end(), f.begin(), f.end());
  }
  require_close(frames, flatten(want.frames), 1e-5, "C");

  std::mt19937 rng(11);
  SECTION("from the frames' gradient") {
    const std::vector<double> r = uniform(9 * 20, rng, -1.0, 1.0);
    const std::vector<gpu::Buffer> grads = frame_grads(ctx, r, 3, 60);
    std::vector<const gpu::Buffer*> ptrs;
    for (auto& g : grads) ptrs.push_back(&g);
    model.backward_from_frames(cmd, ptrs, 0.5f);
    cmd.submit();
    auto loss = [&] {
      const auto f = flatten(ref::ldi_frames(c.net, c.events, 0.0, 1.0, c.times, c.crop, c.blurry).frames);
      double s = 0;
      for (size_t i = 0; i < f.size(); ++i) s += 0.5 * r[i] * f[i];
      return s;
    };
    require_weight_grads(model, c.net, loss);
  }
  SECTION("from the regression of log E to a target") {
    const std::vector<double> d = uniform(3 * 20, rng, 0.5, 2.0);
    gpu::Buffer target(ctx, d.size() * 4, "target");
    target.write(to_float(d));
    model.backward_from_target(cmd, target, 0.25f);
    cmd.submit();
    auto loss = [&] {
      const auto e = flatten(ref::ldi_frames(c.net, c.events, 0.0, 1.0, c.times, c.crop, c.blurry).integral);
      double s = 0;
      for (size_t i = 0; i < e.size(); ++i) s += 0.25 * std::pow(std::log(e[i]) - std::log(d[i]), 2);
      return s;
    };
    require_weight_grads(model, c.net, loss);
  }
  SECTION("from the frames' gradient and the anchor's regression together") {
    const std::vector<double> r = uniform(9 * 20, rng, -1.0, 1.0), d = uniform(3 * 20, rng, 0.5, 2.0);
    const std::vector<gpu::Buffer> grads = frame_grads(ctx, r, 3, 60);
    std::vector<const gpu::Buffer*> ptrs;
    for (auto& g : grads) ptrs.push_back(&g);
    gpu::Buffer target(ctx, d.size() * 4, "anchor");
    target.write(to_float(d));
    model.backward_from_frames(cmd, ptrs, 0.5f, {&target, 0.75f});
    cmd.submit();
    auto loss = [&] {
      const ref::LdiFrames f = ref::ldi_frames(c.net, c.events, 0.0, 1.0, c.times, c.crop, c.blurry);
      const auto frames = flatten(f.frames), e = flatten(f.integral);
      double s = 0;
      for (size_t i = 0; i < frames.size(); ++i) s += 0.5 * r[i] * frames[i];
      for (size_t i = 0; i < e.size(); ++i) s += 0.75 * std::pow(std::log(e[i]) - std::log(d[i]), 2);
      return s;
    };
    require_weight_grads(model, c.net, loss);
    gpu::Buffer short_target(ctx, 2 * 20 * 4, "short anchor");
    CHECK_THROWS_WITH(model.backward_from_frames(cmd, ptrs, 1.0f, {&short_target, 1.0f}),
                      Catch::Contains("the anchor holds fewer than 3 planes"));
  }
  test::require_no_validation_messages();
}

TEST_CASE("LDI: the neutral initialisation gives E = 1 without events, and bad input is refused", "[ldi][gpu]") {
  auto& ctx = test::gpu_context();
  EventStream none;
  none.width = 6, none.height = 5;
  GpuEvents events(ctx, none, {{0.0, 1.0}}, "no events");
  ldi::LdiModel model(ctx, events, {32, 8, 1}, 6, 5, 2);
  model.init(3);
  gpu::Buffer blurry(ctx, 90 * 4, "blurry_crop");
  blurry.write(std::vector<float>(90, 0.25f));
  gpu::Commands cmd(ctx);
  model.forward(cmd, 0, {0.2, 0.9}, {0, 0, 6, 5}, blurry);
  cmd.submit();
  for (float e : model.integral().read<float>(60)) CHECK(e == Approx(1.0f).epsilon(1e-6));
  for (uint32_t i = 0; i < 2; ++i)
    for (float v : model.frame(i).read<float>(90)) CHECK(v == Approx(0.25f).epsilon(1e-6));

  CHECK_THROWS_WITH(ldi::LdiModel(ctx, events, {16, 8, 1}, 6, 5, 2), Catch::Contains("must start with 32"));
  CHECK_THROWS_WITH(ldi::LdiModel(ctx, events, {32, 8, 1}, 7, 5, 2), Catch::Contains("leaves the 6x5 image"));
  CHECK_THROWS_WITH(model.forward(cmd, 0, {0.2, 0.3, 0.4}, {0, 0, 6, 5}, blurry), Catch::Contains("3 frame times"));
  CHECK_THROWS_WITH(model.forward(cmd, 0, {0.2, 1.5}, {0, 0, 6, 5}, blurry), Catch::Contains("outside view 0"));
  test::require_no_validation_messages();
}

TEST_CASE("LDI view tiles: the kept parts cover the sensor once, each at least the reach inside its tile", "[ldi]") {
  const uint32_t W = 40, H = 30, reach = 3;
  const std::vector<ldi::ViewTile> tiles = ldi::view_tiles(W, H, 13, 11, reach);
  CHECK(tiles.size() > 4);
  std::vector<int> covered(size_t(W) * H, 0);
  for (const ldi::ViewTile& t : tiles) {
    CHECK(t.run.w == 13);
    CHECK(t.run.h == 11);
    REQUIRE(t.run.x + t.run.w <= W);
    REQUIRE(t.run.y + t.run.h <= H);
    // Inside the tile, and `reach` away from its sides except where they are the sensor's.
    CHECK((t.keep.x == 0 || t.keep.x >= t.run.x + reach));
    CHECK((t.keep.y == 0 || t.keep.y >= t.run.y + reach));
    CHECK((t.keep.x + t.keep.w == W || t.keep.x + t.keep.w + reach <= t.run.x + t.run.w));
    CHECK((t.keep.y + t.keep.h == H || t.keep.y + t.keep.h + reach <= t.run.y + t.run.h));
    for (uint32_t y = t.keep.y; y < t.keep.y + t.keep.h; ++y)
      for (uint32_t x = t.keep.x; x < t.keep.x + t.keep.w; ++x) ++covered[size_t(y) * W + x];
  }
  CHECK(std::count(covered.begin(), covered.end(), 1) == int(W * H));
  CHECK(ldi::view_tiles(W, H, 128, 128, reach).size() == 1);  // a tile larger than the sensor: one
  CHECK_THROWS_WITH(ldi::view_tiles(W, H, 6, 11, reach), Catch::Contains("keeps nothing"));
  // Tile sides: the whole axis when it fits, else as few tiles as the largest side allows, each
  // as small as covers the axis: 346 = 2 x 170 kept + 2 x 3, 1000 in 4 tiles of 255.
  CHECK(ldi::view_tile_side(173, 256, reach) == 173);
  CHECK(ldi::view_tile_side(346, 256, reach) == 176);
  CHECK(ldi::view_tile_side(1000, 256, reach) == 255);
  CHECK(ldi::view_tiles(346, 260, 176, ldi::view_tile_side(260, 256, reach), reach).size() == 4);
  CHECK(ldi::view_tiles(1000, 10, 255, 10, reach).size() == 4);
  CHECK(ldi::view_tiles(1000, 10, 254, 10, reach).size() == 5);
  CHECK_THROWS_WITH(ldi::view_tile_side(100, 6, reach), Catch::Contains("keep nothing"));
}

TEST_CASE("LDI view frames: overlapping tiles give what one forward over the whole view gives", "[ldi][gpu]") {
  auto& ctx = test::gpu_context();
  Case c = make_case();  // its weights; denser events on a larger sensor
  const uint32_t W = 40, H = 30;
  EventStream stream;
  stream.width = W, stream.height = H;
  std::mt19937 rng(5);
  std::vector<double> t = uniform(3000, rng, 0.0, 1.0);
  std::sort(t.begin(), t.end());
  for (double ti : t) stream.push(uint16_t(rng() % W), uint16_t(rng() % H), ti, rng() % 3 ? 1 : -1);
  GpuEvents events(ctx, stream, {{0.0, 1.0}}, "random events");
  const std::vector<double> blurry_v = uniform(3 * W * H, rng, 0.1, 0.9);
  gpu::Buffer blurry(ctx, blurry_v.size() * 4, "blurry");
  blurry.write(to_float(blurry_v));
  // The reference: one model over the whole sensor.
  ldi::LdiModel whole(ctx, events, c.net.widths, W, H, 3);
  set_weights(whole, c.net);
  gpu::Commands cmd(ctx);
  whole.forward(cmd, 0, c.times, {0, 0, W, H}, blurry);
  // The source of the weights is a crop-sized model, as in training.
  ldi::LdiModel source(ctx, events, c.net.widths, 8, 8, 3);
  set_weights(source, c.net);
  ldi::FullViewFrames tiled(ctx, events, c.net.widths, 13, 11, 3);
  REQUIRE(tiled.reach() == 3);
  REQUIRE(tiled.tiles().size() > 4);
  tiled.forward(cmd, source, 0, c.times, blurry);
  cmd.submit();
  for (uint32_t i = 0; i < 3; ++i) {
    const std::vector<float> want = whole.frame(i).read<float>(3 * W * H), got = tiled.frame(i).read<float>(3 * W * H);
    double worst = 0, largest = 0;
    for (size_t k = 0; k < want.size(); ++k) {
      worst = std::max(worst, std::abs(double(got[k]) - want[k]));
      largest = std::max(largest, std::abs(double(want[k])));
    }
    WARN("frame " << i << ": largest difference " << worst << " of values up to " << largest);
    CHECK(worst <= 1e-6 * largest);
  }
  CHECK_THROWS_WITH(ldi::FullViewFrames(ctx, events, {32, 8, 8, 8, 1}, 8, 8, 1), Catch::Contains("keeps nothing"));
  test::require_no_validation_messages();
}
