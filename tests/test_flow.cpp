// Optical flow from events (engine/flow): the contrast and its gradient against the double
// reference, the node grid, the pixel layout of the events, and the recovery of known motions.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <random>

#include "cli_helpers.h"
#include "events/event_model.h"
#include "flow/flow_estimator.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "reference/flow_reference.h"
#include "sim/flow_truth.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

// Soft-edged discs of random size and grey level on a mid-grey ground: edges in every direction.
struct Texture {
  struct Disc {
    double x, y, r, level;
  };
  std::vector<Disc> discs;
  explicit Texture(uint32_t seed, double w, double h) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(-0.2 * w, 1.2 * w), uy(-0.2 * h, 1.2 * h), ur(3, 9), ul(0.05, 0.9);
    for (int i = 0; i < 60; ++i) discs.push_back({ux(rng), uy(rng), ur(rng), ul(rng)});
  }
  double operator()(double x, double y) const {
    double v = 0.4;
    for (const Disc& d : discs) {
      const double s = std::clamp(d.r - std::hypot(x - d.x, y - d.y) + 0.5, 0.0, 1.0);  // 1 px soft edge
      v = v * (1 - s) + d.level * s;
    }
    return v;
  }
};

// Events of an ideal sensor watching `tex` seen through `motion` (the texture point seen at pixel
// centre (x, y) at normalised time t), exposure [0, 1], sampled finely.
EventStream simulate(uint32_t W, uint32_t H, const Texture& tex,
                     const std::function<void(double, double, double, double&, double&)>& motion) {
  events::EventSimulator sim(W, H, events::EventModelParams::ideal(), 1);
  std::vector<double> frame(size_t(W) * H);
  const int steps = 400;
  for (int k = 0; k <= steps; ++k) {
    const double t = double(k) / steps;
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < W; ++x) {
        double sx, sy;
        motion(x + 0.5, y + 0.5, t, sx, sy);
        frame[size_t(y) * W + x] = tex(sx, sy);
      }
    sim.add_frame(frame.data(), t);
  }
  return sim.take_events();
}

std::vector<double> uniform_frames(int intervals) {
  std::vector<double> u;
  for (int i = 0; i <= intervals; ++i) u.push_back(double(i) / intervals);
  return u;
}

// Mean endpoint error over the pixels with events in each interval, against flow(x, y, i).
double mean_aee(const flow::ExposureFlow& f, const flow::PixelEvents& ev,
                const std::function<void(double, double, size_t, double&, double&)>& truth) {
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < f.intervals.size(); ++i) {
    const std::vector<float> d = flow::dense_flow(f.intervals[i].grid, f.width, f.height);
    const std::vector<uint32_t> counts = flow::event_counts(ev, f.frame_u[i], f.frame_u[i + 1]);
    for (uint32_t y = 0; y < f.height; ++y)
      for (uint32_t x = 0; x < f.width; ++x) {
        const size_t p = size_t(y) * f.width + x;
        if (!counts[p]) continue;
        double u, v;
        truth(x + 0.5, y + 0.5, i, u, v);
        sum += std::hypot(d[p * 2] - u, d[p * 2 + 1] - v);
        ++n;
      }
  }
  return n ? sum / n : 1e9;
}

flow::FlowOptions small_options() {
  flow::FlowOptions o;
  o.tiles = {1};
  o.image_scale = {1};
  o.event_stride = {1};
  o.iterations = {100};
  o.temporal_weight = 1.0;  // the motions below are uniform in time: no coarse-to-fine in time
  o.time_groups = {}, o.time_iterations = {};
  o.lr_intervals = 2.5e-4;  // of the diagonal: 0.02 px at 64x48
  o.interval_iterations = 20;
  return o;
}

}  // namespace

TEST_CASE("flow: events are laid out pixel by pixel in time order, times normalised", "[flow]") {
  EventStream s;
  s.width = 3, s.height = 2;
  s.push(2, 1, 10.0, 1), s.push(0, 0, 10.5, -1), s.push(2, 1, 11.0, -1), s.push(1, 0, 12.0, 1), s.push(2, 1, 14.0, 1);
  const flow::PixelEvents ev = flow::pixel_events(s, 10.0, 14.0, "s");
  REQUIRE(ev.first == std::vector<uint32_t>{0, 1, 2, 2, 2, 2, 4});
  REQUIRE(ev.time == std::vector<float>{0.125f, 0.5f, 0.0f, 0.25f});
  REQUIRE(ev.order == std::vector<uint32_t>{5, 0, 1});
  REQUIRE(flow::event_counts(ev, 0.1, 0.3) == std::vector<uint32_t>{1, 0, 0, 0, 0, 1});
  REQUIRE_THROWS_WITH(flow::pixel_events(s, 3.0, 3.0, "cam.h5"), Catch::Contains("cam.h5") && Catch::Contains("empty"));
}

TEST_CASE("flow: a refined grid is the same field", "[flow]") {
  flow::FlowGrid g(2);
  std::mt19937 rng(3);
  for (float& v : g.nodes) v = std::uniform_real_distribution<float>(-2, 2)(rng);
  const std::vector<float> a = flow::dense_flow(g, 37, 23), b = flow::dense_flow(flow::refine(g, 8, 37, 23), 37, 23);
  for (size_t i = 0; i < a.size(); ++i) REQUIRE(b[i] == Approx(a[i]).margin(1e-5));
  flow::FlowOptions bad;
  bad.tiles = {2, 3};
  bad.iterations = {1, 1};
  REQUIRE_THROWS_WITH(bad.validate(), Catch::Contains("multiple"));
  flow::FlowOptions groups;
  groups.time_iterations = {20};
  REQUIRE_THROWS_WITH(groups.validate(), Catch::Contains("grouping"));
  groups.time_iterations = {20, 20, 20};
  groups.time_groups = {2, 0, 6};
  REQUIRE_THROWS_WITH(groups.validate(), Catch::Contains("groups must be >= 1"));
}

TEST_CASE("flow: the GPU contrast and its node gradients match the double reference", "[flow][gpu]") {
  const uint32_t W = 40, H = 30;
  const Texture tex(5, W, H);
  const EventStream s = simulate(
      W, H, tex, [](double x, double y, double t, double& sx, double& sy) { sx = x - 4.0 * t, sy = y + 2.5 * t; });
  const flow::PixelEvents ev = flow::pixel_events(s, 0.0, 1.0, "sim");
  REQUIRE(ev.size() > 500);
  const std::vector<double> frame_u = {0.0, 0.3, 0.55, 1.0};
  std::vector<flow::FlowGrid> grids(3, flow::FlowGrid(2));
  std::mt19937 rng(7);
  for (auto& g : grids)
    for (float& v : g.nodes) v = std::uniform_real_distribution<float>(-1.5f, 1.5f)(rng);
  const std::vector<double> scale = {-0.3, -0.5, 0.2};
  flow::FlowEstimator est(test::gpu_context());
  est.set_events(ev);
  // The sensor's images with every event, and the coarse levels' settings: half-size images
  // from every third event.
  const auto [image_scale, stride] = GENERATE(std::pair<int, uint32_t>{1, 1}, std::pair<int, uint32_t>{2, 3});
  INFO("image scale " << image_scale << ", event stride " << stride);
  auto reference = [&](const std::vector<flow::FlowGrid>& g) {
    return reference::flow_contrast(ev, frame_u, g, scale, image_scale, stride);
  };
  const flow::ContrastEval gpu =
      est.evaluate(frame_u, grids, std::vector<float>(scale.begin(), scale.end()), true, image_scale, stride);
  double value = 0;
  for (size_t i = 0; i < scale.size(); ++i) value += scale[i] * gpu.g[i];
  REQUIRE(value == Approx(reference(grids)).epsilon(1e-4));
  double max_grad = 0;
  for (auto& g : gpu.node_grad)
    for (double v : g) max_grad = std::max(max_grad, std::abs(v));
  REQUIRE(max_grad > 0);
  const double h = 1e-4;
  for (size_t j = 0; j < grids.size(); ++j)
    for (size_t k = 0; k < grids[j].nodes.size(); ++k) {
      auto plus = grids, minus = grids;
      plus[j].nodes[k] += float(h);
      minus[j].nodes[k] -= float(h);
      const double fd = (reference(plus) - reference(minus)) / double(plus[j].nodes[k] - minus[j].nodes[k]);
      INFO("interval " << j << " node value " << k);
      // Relative to each node's own gradient, with a small floor for nodes near zero.
      CHECK(gpu.node_grad[j][k] == Approx(fd).epsilon(0.02).margin(2e-3 * max_grad));
    }
  test::require_no_validation_messages();
}

TEST_CASE("flow: a translating texture's flow is recovered within 0.1 px", "[flow][gpu]") {
  const uint32_t W = 64, H = 48;
  const double vx = 1.2, vy = -0.7;  // pixels per interval, 6 intervals
  const EventStream s = simulate(W, H, Texture(11, W, H), [&](double x, double y, double t, double& sx, double& sy) {
    sx = x - 6 * vx * t, sy = y - 6 * vy * t;
  });
  const flow::PixelEvents ev = flow::pixel_events(s, 0.0, 1.0, "sim");
  flow::FlowEstimator est(test::gpu_context(), small_options());
  const flow::ExposureFlow f = est.estimate(ev, uniform_frames(6));
  REQUIRE(f.intervals.size() == 6);
  CHECK(f.contrast > 1.5);
  const double aee = mean_aee(f, ev, [&](double, double, size_t, double& u, double& v) { u = vx, v = vy; });
  INFO("mean endpoint error " << aee << " px");
  CHECK(aee < 0.1);
  test::require_no_validation_messages();
}

TEST_CASE("flow: a rotating texture's flow is recovered within 0.1 px", "[flow][gpu]") {
  const uint32_t W = 64, H = 48;
  const double cx = 30, cy = 26, omega = 6 * 0.03;  // radians over the exposure: 0.03 per interval
  auto rotate = [&](double x, double y, double a, double& rx, double& ry) {
    rx = cx + std::cos(a) * (x - cx) - std::sin(a) * (y - cy);
    ry = cy + std::sin(a) * (x - cx) + std::cos(a) * (y - cy);
  };
  const EventStream s = simulate(W, H, Texture(12, W, H), [&](double x, double y, double t, double& sx, double& sy) {
    rotate(x, y, -omega * t, sx, sy);  // the scene turns by +omega t
  });
  const flow::PixelEvents ev = flow::pixel_events(s, 0.0, 1.0, "sim");
  flow::FlowEstimator est(test::gpu_context(), small_options());
  const flow::ExposureFlow f = est.estimate(ev, uniform_frames(6));
  const double aee = mean_aee(f, ev, [&](double x, double y, size_t, double& u, double& v) {
    double rx, ry;
    rotate(x, y, omega / 6, rx, ry);
    u = rx - x, v = ry - y;
  });
  INFO("mean endpoint error " << aee << " px");
  CHECK(aee < 0.1);
  test::require_no_validation_messages();
}

TEST_CASE("flow: the default schedule finds each interval's flow of a simulated shaken exposure", "[flow][gpu][cli]") {
  // The simulator's shake often turns round near the exposure's ends, so the end intervals move
  // against the middle ones: each interval's own flow must be found, not the exposure's mean.
  // The default scene at the sensor's size, a seed no setting was chosen on.
  const fs::path dir = test::fresh_dir("flow_schedule");
  std::string log;
  REQUIRE(test::run_evflow(dir, "simulate --out sim --seed 5 --train-views 2 --novel-views 1", log) == 0);
  const io::Dataset data = io::load_dataset(dir / "sim");
  flow::FlowEstimator est(test::gpu_context());
  const std::vector<double> u = uniform_frames(6);
  double all = 0;
  size_t all_n = 0;
  for (const io::View& view : data.train) {
    const flow::PixelEvents ev = flow::pixel_events(data.events, view.exposure_start, view.exposure_end, view.name);
    const flow::ExposureFlow f = est.estimate(ev, u);
    const auto truth = sim::ground_truth_interval_flow(dir / "sim", view.name, u);
    REQUIRE(truth);
    for (size_t i = 0; i < f.intervals.size(); ++i) {
      const std::vector<float> d = flow::dense_flow(f.intervals[i].grid, f.width, f.height);
      const sim::EndpointError e = sim::endpoint_error(d, (*truth)[i], flow::event_counts(ev, u[i], u[i + 1]));
      INFO("view " << view.name << " interval " << i << ": endpoint error " << e.mean() << " px, flow "
                   << e.truth_mean() << " px, " << e.n << " pixels");
      REQUIRE(e.n > 10000);
      CHECK(e.mean() < 0.9);
      all += e.sum, all_n += e.n;
    }
  }
  INFO("mean endpoint error " << all / all_n << " px");
  CHECK(all / all_n < 0.45);
  fs::remove_all(dir);
  test::require_no_validation_messages();
}

TEST_CASE("flow: an exposure without events keeps zero flow and one event moves it at most a pixel", "[flow][gpu]") {
  EventStream s;
  s.width = 24, s.height = 16;
  flow::FlowEstimator est(test::gpu_context(), small_options());
  for (int events : {0, 1}) {
    INFO(events << " events");
    if (events) s.push(5, 7, 0.5, 1);
    const flow::PixelEvents ev = flow::pixel_events(s, 0.0, 1.0, "sim");
    REQUIRE(ev.size() == size_t(events));
    const flow::ExposureFlow f = est.estimate(ev, uniform_frames(6));
    REQUIRE(f.intervals.size() == 6);
    // No events: nothing to sharpen, the flow stays zero and the contrast 1. One event: its
    // sharpness depends only on where its bilinear vote lands, so the flow may move it towards a
    // pixel centre, no further.
    CHECK(std::isfinite(f.contrast));
    if (events == 0) CHECK(f.contrast == 1.0);
    for (const auto& i : f.intervals)
      for (float v : i.grid.nodes) {
        REQUIRE(std::isfinite(v));
        CHECK(std::abs(v) <= (events == 0 ? 0.0f : 1.0f));
      }
  }
  test::require_no_validation_messages();
}
