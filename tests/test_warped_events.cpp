// The warped-event loss (engine/loss/warped_event_loss.h) and the events it compares
// (engine/events/warped_events.h): hand-worked votes, value and gradients against the double
// reference with finite differences, and an edge placed where the warped events stack.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include <unistd.h>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "events/event_model.h"
#include "events/warped_events.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "loss/warped_event_loss.h"
#include "plot/curve_plot.h"

#include <nlohmann/json.hpp>
#include "reference/warped_event_reference.h"

using namespace evflow;

namespace {

struct Run {
  double value = 0;
  std::vector<std::vector<float>> grad;  // per frame, the term's share (initial values removed)
};

// Records the term once on planar RGB frames; gradients start at a known pattern so that "adds
// into" is checked too.
Run run_gpu(uint32_t W, uint32_t H, const std::vector<std::vector<float>>& frames, const std::vector<float>& planes,
            float weight, uint32_t pool = 1) {
  auto& ctx = test::gpu_context();
  const uint32_t F = uint32_t(frames.size());
  const size_t n = frames[0].size();
  WarpedEventOptions opt;
  opt.pool = pool;
  WarpedEventLoss loss(ctx, W, H, {planes}, weight, opt);
  std::vector<gpu::Buffer> rgb, grad;
  std::vector<float> init(n);
  for (size_t i = 0; i < n; ++i) init[i] = 0.01f * float(i % 7);
  for (uint32_t i = 0; i < F; ++i) {
    rgb.emplace_back(ctx, n * 4, "frame");
    rgb.back().write(frames[i]);
    grad.emplace_back(ctx, n * 4, "frame_grad");
    grad.back().write(init);
  }
  ExposureFrames f;
  f.width = W, f.height = H, f.t0 = 0.0, f.t1 = 1.0;
  f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&rgb[i]), f.grad.push_back(&grad[i]);
  gpu::Commands cmd(ctx);
  loss.record(cmd, f);
  cmd.submit();
  Run r;
  r.value = loss.value();
  for (uint32_t i = 0; i < F; ++i) {
    auto g = grad[i].read<float>(n);
    for (size_t k = 0; k < n; ++k) g[k] -= init[k];
    r.grad.push_back(g);
  }
  return r;
}

reference::WarpedEventInputs reference_inputs(uint32_t W, uint32_t H, const std::vector<std::vector<float>>& frames,
                                              const std::vector<float>& planes) {
  reference::WarpedEventInputs in;
  in.width = W, in.height = H;
  const size_t hw = size_t(W) * H;
  for (auto& fr : frames) in.frames.emplace_back(fr.begin(), fr.end());
  for (size_t i = 0; i + 1 < frames.size(); ++i) {
    auto plane = [&](size_t k) {
      return std::vector<double>(planes.begin() + (3 * i + k) * hw, planes.begin() + (3 * i + k + 1) * hw);
    };
    in.m.push_back(plane(0)), in.dx.push_back(plane(1)), in.dy.push_back(plane(2));
  }
  return in;
}

void check_against_reference(uint32_t W, uint32_t H, const std::vector<std::vector<float>>& frames,
                             const std::vector<float>& planes, uint32_t seed, uint32_t pool = 1) {
  const float weight = 0.7f;
  const Run r = run_gpu(W, H, frames, planes, weight, pool);
  reference::WarpedEventInputs in = reference_inputs(W, H, frames, planes);
  in.pool = pool;
  const double ref_value = reference::warped_event_loss(in);
  INFO("gpu " << r.value << " reference " << ref_value);
  REQUIRE(std::abs(r.value - ref_value) <= 1e-4 * std::max(1.0, ref_value));

  // Central differences of the double reference at sampled (frame, element) entries, half of
  // them where the gradient is largest.
  std::mt19937 rng(seed);
  double max_scale = 0;
  std::vector<std::pair<size_t, size_t>> entries;
  for (size_t fi = 0; fi < frames.size(); ++fi)
    for (size_t e = 0; e < frames[0].size(); ++e) {
      max_scale = std::max(max_scale, double(std::abs(r.grad[fi][e])) / weight);
      entries.emplace_back(fi, e);
    }
  std::shuffle(entries.begin(), entries.end(), rng);
  entries.resize(60);
  int bad = 0;
  for (auto [fi, e] : entries) {
    const double h = 1e-6, x0 = in.frames[fi][e];
    in.frames[fi][e] = x0 + h;
    const double lp = reference::warped_event_loss(in);
    in.frames[fi][e] = x0 - h;
    const double lm = reference::warped_event_loss(in);
    in.frames[fi][e] = x0;
    const double fd = (lp - lm) / (2 * h), gpu = double(r.grad[fi][e]) / weight;
    if (std::abs(gpu - fd) > 2e-3 * std::abs(fd) + 1e-4 * max_scale) {
      ++bad;
      UNSCOPED_INFO("frame " << fi << " element " << e << ": gpu " << gpu << " fd " << fd);
    }
  }
  REQUIRE(bad == 0);
  REQUIRE(max_scale > 0);
  for (float g : r.grad[0]) REQUIRE(g == 0.0f);  // frame 0 ends no interval
}

std::vector<std::vector<float>> random_frames(uint32_t W, uint32_t H, uint32_t F, uint32_t seed, bool flat) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.05f, 0.95f);
  std::vector<std::vector<float>> frames(F, std::vector<float>(size_t(3) * W * H));
  for (auto& fr : frames)
    for (auto& v : fr) v = flat ? 0.5f : u(rng);
  return frames;
}

// Per interval: M (signed multiples of 0.2), dx, dy in [-2, 2].
std::vector<float> random_planes(uint32_t W, uint32_t H, uint32_t intervals, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> count(-3, 3);
  std::uniform_real_distribution<float> d(-2.0f, 2.0f);
  const size_t hw = size_t(W) * H;
  std::vector<float> planes;
  for (uint32_t i = 0; i < intervals; ++i) {
    for (size_t p = 0; p < hw; ++p) planes.push_back(0.2f * float(count(rng)));
    for (size_t p = 0; p < 2 * hw; ++p) planes.push_back(d(rng));
  }
  return planes;
}

}  // namespace

TEST_CASE("warped events: each event votes bilinearly where the flow carries it by the interval's end",
          "[events][warp]") {
  EventStream s;
  s.width = 8, s.height = 6;
  s.push(2, 3, 0.0, 1);   // lever 1: the whole displacement, to x = 3.5
  s.push(2, 3, 0.5, -1);  // lever 1/2: to x = 2.75
  s.push(5, 1, 0.6, 1);   // its pixel's flow is NaN: dropped
  s.push(7, 5, 0.8, 1);   // carried off the sensor (x = 7.3): only its in-sensor share is lost
  s.push(1, 1, 1.0, 1);   // t = tb: not in [ta, tb)
  std::vector<float> d(8 * 6 * 2);
  for (size_t p = 0; p < 48; ++p) d[2 * p] = 1.5f, d[2 * p + 1] = 0.0f;
  d[2 * (1 * 8 + 5)] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> m = warp_events_to_end(s, 0.0, 1.0, d, 0.2, 0.3);
  std::vector<float> want(48, 0.0f);
  want[3 * 8 + 3] = 0.1f - 0.225f;  // halves of +0.2, and 3/4 of -0.3
  want[3 * 8 + 4] = 0.1f;
  want[3 * 8 + 2] = -0.075f;
  want[5 * 8 + 7] = 0.2f * 0.7f;  // x' = 7.3: 0.7 stays on column 7, 0.3 falls off
  for (size_t p = 0; p < 48; ++p) {
    INFO("pixel " << p);
    CHECK(m[p] == Approx(want[p]).margin(1e-6));
  }
  CHECK_THROWS_WITH(warp_events_to_end(s, 0.0, 1.0, std::vector<float>(10), 0.2, 0.2),
                    Catch::Contains("displacement field has 10 values"));
}

TEST_CASE("warped-event loss value and frame gradients match the double reference (finite differences)",
          "[events][warp][loss]") {
  const uint32_t W = 20, H = 14;
  SECTION("seven frames") {
    check_against_reference(W, H, random_frames(W, H, 7, 11, false), random_planes(W, H, 6, 3), 17);
  }
  SECTION("five frames (N = 2)") {
    check_against_reference(W, H, random_frames(W, H, 5, 12, false), random_planes(W, H, 4, 4), 18);
  }
  SECTION("flat frames: the render-side norm sits on its floor") {
    auto frames = random_frames(W, H, 5, 13, true);
    for (size_t k = 0; k < frames[2].size(); k += 5) frames[2][k] = 0.51f;  // a few tiny edges
    check_against_reference(W, H, frames, random_planes(W, H, 4, 5), 19);
  }
  SECTION("pooled over 3 x 3 cells, the last ones cut by the border") {
    check_against_reference(W, H, random_frames(W, H, 7, 14, false), random_planes(W, H, 6, 6), 20, 3);
  }
  SECTION("pooled over 4 x 4 cells") {
    check_against_reference(W, H, random_frames(W, H, 5, 15, false), random_planes(W, H, 4, 7), 21, 4);
  }
  test::require_no_validation_messages();
}

namespace {

// A vertical edge (dark left, bright right, 0.7 px soft) at x = e(t) = 14 + 12 t over a 48 x 8
// sensor, its events from an ideal sensor, and the renders of the edge at e(t) + shift.
struct MovingEdge {
  static constexpr uint32_t W = 48, H = 8;
  static double edge(double t) { return 14.0 + 12.0 * t; }
  static double brightness(double x, double e) { return 0.1 + 0.7 / (1.0 + std::exp(-(x - e) / 0.7)); }
  static EventStream events() {
    events::EventSimulator sim(W, H, events::EventModelParams::ideal(), 1);
    std::vector<double> frame(size_t(W) * H);
    for (int k = 0; k <= 600; ++k) {
      const double t = k / 600.0;
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) frame[size_t(y) * W + x] = brightness(x, edge(t));
      sim.add_frame(frame.data(), t);
    }
    return sim.take_events();
  }
  static std::vector<std::vector<float>> renders(const std::vector<double>& u, double shift) {
    std::vector<std::vector<float>> out;
    for (double t : u) {
      std::vector<float> f(size_t(3) * W * H);
      for (uint32_t c = 0; c < 3; ++c)
        for (uint32_t y = 0; y < H; ++y)
          for (uint32_t x = 0; x < W; ++x) f[(c * H + y) * W + x] = float(brightness(x, edge(t) + shift));
      out.push_back(f);
    }
    return out;
  }
};

}  // namespace

TEST_CASE("warped-event loss: renders whose edges sit where the warped events stack score best",
          "[events][warp][loss]") {
  const uint32_t W = MovingEdge::W, H = MovingEdge::H;
  const std::vector<double> u = ExposureTrajectory::virtual_times(3);
  const EventStream ev = MovingEdge::events();
  REQUIRE(ev.size() > 100);
  // The true flow: 2 px to the right per interval.
  std::vector<float> d(size_t(W) * H * 2);
  for (size_t p = 0; p < size_t(W) * H; ++p) d[2 * p] = 2.0f, d[2 * p + 1] = 0.0f;
  std::vector<float> planes;
  for (size_t i = 0; i + 1 < u.size(); ++i) {
    const std::vector<float> m = warp_events_to_end(ev, u[i], u[i + 1], d, 0.2, 0.2);
    planes.insert(planes.end(), m.begin(), m.end());
    for (size_t c = 0; c < 2; ++c)
      for (size_t p = 0; p < size_t(W) * H; ++p) planes.push_back(d[2 * p + c]);
  }
  const double right = run_gpu(W, H, MovingEdge::renders(u, 0.0), planes, 1.0f).value;
  const double behind = run_gpu(W, H, MovingEdge::renders(u, -3.0), planes, 1.0f).value;
  const double ahead = run_gpu(W, H, MovingEdge::renders(u, 3.0), planes, 1.0f).value;
  // The loss is lowest where the renders' edges sit where the warped events stack.
  INFO("loss at the true edge " << right << ", 3 px behind " << behind << ", 3 px ahead " << ahead);
  CHECK(right < 0.25);
  CHECK(behind > 4 * right);
  CHECK(ahead > 4 * right);
  test::require_no_validation_messages();
}

TEST_CASE("blur+events+warp and +flow train on a simulated folder with ground-truth and estimated flow (cached)",
          "[events][warp][train][gpu]") {
  namespace fs = std::filesystem;
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_warp_train");
  std::string out;
  REQUIRE(test::run_evflow(dir,
                           "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 4 --seed 3 "
                           "--train-views 3 --novel-views 1",
                           out) == 0);
  auto train = [&](const std::string& data, const std::string& run, const std::string& flow,
                   const std::string& method = "blur+events+warp") {
    const std::string a = "train " + data + " --out " + run + " method=" + method +
                          " event_from=0 iterations=4 init_gaussians=300 max_gaussians=600 "
                          "sh_degree=0 flow=" +
                          flow;
    const int rc = test::run_evflow(dir, a, out);
    INFO(a << "\n" << out);
    REQUIRE(rc == 0);
    return plot::read_curve_csv(dir / run / "curve.csv");
  };
  auto check_term = [](const plot::CurveTable& t) {
    const int w = t.column("events_warped");
    REQUIRE(w >= 0);
    REQUIRE(t.rows.size() == 4);
    for (const auto& row : t.rows) {
      CHECK(row[size_t(w)] > 0.0);  // normalised images: 0 only when they agree exactly
      CHECK(row[size_t(w)] < 4.0);  // 4: exactly opposed
    }
  };
  const plot::CurveTable plain_mean = train("sim", "gt", "gt");
  check_term(plain_mean);
  CHECK(out.find("estimated") == std::string::npos);
  // With the flow-upsampled blur (2NM+1 = 13 frames in the mean) as well.
  check_term(train("sim", "gt_flow", "gt", "blur+events+flow"));
  CHECK(test::slurp(dir / "gt_flow" / "config.json").find("\"blur_upsample\": 4") != std::string::npos);
  // upsample_from=0.5: the plain mean for steps 1-2 (the same run as blur+events+warp), the
  // upsampled blur from step 3.
  const plot::CurveTable late = train("sim", "gt_late", "gt upsample_from=0.5", "blur+events+flow");
  const int loss = late.column("loss");
  REQUIRE(loss >= 0);
  REQUIRE(late.rows.size() == 4);
  for (size_t r = 0; r < 2; ++r)
    CHECK(late.rows[r][size_t(loss)] == Approx(plain_mean.rows[r][size_t(loss)]).epsilon(1e-4));
  CHECK(std::abs(late.rows[2][size_t(loss)] / plain_mean.rows[2][size_t(loss)] - 1.0) > 1e-3);

  // `evflow flow` estimates every view, scores it against the ground truth and fills the cache
  // that training with flow=events reads.
  REQUIRE(test::run_evflow(dir, "flow sim --out F --json", out) == 0);
  const nlohmann::json j = nlohmann::json::parse(out.substr(out.find('{')));
  const double aee = j["aee_px"].get<double>();
  INFO("average endpoint error " << aee << " px");
  CHECK(std::isfinite(aee));
  CHECK(aee < 1.0);
  CHECK(j["iwe_variance_after"].get<double>() > j["iwe_variance_before"].get<double>());
  CHECK(fs::exists(dir / "F" / "000" / "flow_05.npy"));
  auto cached = [&] {
    size_t n = 0;
    for (auto& e : fs::directory_iterator(dir / "sim" / ".evflow-cache" / "flow")) n += e.path().extension() == ".npy";
    return n;
  };
  CHECK(cached() == 3);
  check_term(train("sim", "ev", "events"));
  CHECK(out.find("flow: view") == std::string::npos);
  // Without the cache: estimated once per view, then read back.
  fs::remove_all(dir / "sim" / ".evflow-cache");
  check_term(train("sim", "ev2", "events"));
  size_t estimated = 0;
  for (size_t at = out.find("flow: view"); at != std::string::npos; at = out.find("flow: view", at + 1)) ++estimated;
  CHECK(estimated == 3);
  CHECK(cached() == 3);
  check_term(train("sim", "ev3", "events"));
  CHECK(out.find("flow: view") == std::string::npos);

  // The model's flow (flow=model): computed at step 1 and every 2 steps after; mixed: the ground
  // truth for steps 1-2, the model's flow from step 3 (flow_model_from=0.5 of 4 steps).
  auto model_flow_steps = [&] {
    std::vector<int> steps;
    for (size_t at = out.find("model's flow of 3 views at step "); at != std::string::npos;
         at = out.find("model's flow of 3 views at step ", at + 1))
      steps.push_back(std::atoi(out.c_str() + at + 32));
    return steps;
  };
  check_term(train("sim", "model", "model flow_refresh=2"));
  CHECK(model_flow_steps() == std::vector<int>{1, 3});
  check_term(train("sim", "model_flow", "model flow_refresh=3", "blur+events+flow"));
  CHECK(model_flow_steps() == std::vector<int>{1, 4});
  check_term(train("sim", "mixed", "gt flow_model_from=0.5 flow_refresh=5"));
  CHECK(model_flow_steps() == std::vector<int>{3});
  CHECK(test::run_evflow(dir, "train sim --out bad method=blur+events+warp flow=model flow_model_from=0.5", out) != 0);
  CHECK(out.find("with flow=model it must be 0") != std::string::npos);

  // Without the simulator's ground truth, flow=gt is refused by name.
  fs::remove_all(dir / "sim" / "gt");
  const int rc = test::run_evflow(dir, "train sim --out nogt method=blur+events+warp iterations=1 flow=gt", out);
  CHECK(rc != 0);
  CHECK(out.find("flow=gt needs the simulator's ground truth") != std::string::npos);
  fs::remove_all(dir);
}
