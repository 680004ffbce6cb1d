// The event loss (engine/loss/event_loss.h): value and gradients against the double reference
// with finite differences, the pair sampling, and the sign convention against the simulator.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>

#include <unistd.h>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "events/event_model.h"
#include "events/gpu_events.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "io/image.h"
#include "loss/event_loss.h"
#include "plot/curve_plot.h"
#include "reference/event_reference.h"
#include "train/image_model.h"
#include "train/loss_terms.h"
#include "train/train_layout.h"

using namespace evflow;

namespace {

EventStream random_events(uint32_t w, uint32_t h, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<double> t(n);
  for (auto& v : t) v = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  std::sort(t.begin(), t.end());
  EventStream ev;
  ev.width = w, ev.height = h;
  for (size_t i = 0; i < n; ++i)
    ev.push(uint16_t(rng() % w), uint16_t(rng() % h), t[i], (rng() & 1) ? int8_t(1) : int8_t(-1));
  return ev;
}

// Counts per interval [time(k), time(k+1)) on the host, as the reference wants them.
void host_counts(const EventStream& ev, const ExposureFrames& f, reference::EventLossInputs& in) {
  const size_t hw = size_t(ev.width) * ev.height;
  for (size_t k = 0; k + 1 < f.u.size(); ++k) {
    std::vector<int> pos(hw, 0), neg(hw, 0);
    auto [a, b] = ev.window(f.time_at(k), f.time_at(k + 1));
    for (size_t i = a; i < b; ++i) (ev.p[i] > 0 ? pos : neg)[size_t(ev.y[i]) * ev.width + ev.x[i]]++;
    in.pos.push_back(pos), in.neg.push_back(neg);
  }
}

// An exposure over [t0, t1] whose 2N+1 = rgb.size() frames are `rgb`, in time-reversed order when
// `reversed` (as the trainer's direction check scores them), with gradients into `grad` when given.
ExposureFrames exposure_of(std::vector<gpu::Buffer>& rgb, std::vector<gpu::Buffer>* grad, uint32_t w, uint32_t h,
                           uint32_t view, EventWindow window, uint64_t seed, bool reversed) {
  const uint32_t F = uint32_t(rgb.size());
  ExposureFrames f;
  f.view = view;
  f.width = w, f.height = h;
  f.t0 = window.t0, f.t1 = window.t1;
  f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
  f.seed = seed;
  for (uint32_t i = 0; i < F; ++i) {
    f.rgb.push_back(&rgb[reversed ? F - 1 - i : i]);
    if (grad) f.grad.push_back(&(*grad)[i]);
  }
  return f;
}

struct Run {
  double value = 0;
  std::vector<std::vector<float>> grad;  // per frame, the term's share (initial values removed)
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
};

// Records the term on planar RGB frames; gradients start at a known pattern so that "adds into"
// is checked too.
Run run_gpu(const EventStream& ev, const std::vector<std::vector<float>>& frames, const EventLossOptions& opt,
            float weight, uint64_t seed) {
  auto& ctx = test::gpu_context();
  const uint32_t F = uint32_t(frames.size());
  const size_t n = frames[0].size();
  GpuEvents gev(ctx, ev, {EventWindow{0.0, 1.0}}, "test events");
  EventLoss loss(ctx, gev, weight, opt);
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
  f.width = ev.width, f.height = ev.height, f.t0 = 0.0, f.t1 = 1.0;
  f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&rgb[i]), f.grad.push_back(&grad[i]);
  f.seed = seed;
  gpu::Commands cmd(ctx);
  loss.record(cmd, f);
  cmd.submit();
  Run r;
  r.value = loss.value();
  r.pairs = loss.last_pairs();
  for (uint32_t i = 0; i < F; ++i) {
    auto g = grad[i].read<float>(n);
    for (size_t k = 0; k < n; ++k) g[k] -= init[k];
    r.grad.push_back(g);
  }
  return r;
}

void check_against_reference(const EventStream& ev, const std::vector<std::vector<float>>& frames, uint64_t seed,
                             uint32_t pool = 1) {
  EventLossOptions opt;
  opt.theta_pos = 0.2f, opt.theta_neg = 0.3f;
  opt.pool = pool;
  const float weight = 0.7f;
  Run r = run_gpu(ev, frames, opt, weight, seed);

  reference::EventLossInputs in;
  in.width = ev.width, in.height = ev.height;
  for (auto& fr : frames) in.frames.emplace_back(fr.begin(), fr.end());
  ExposureFrames f;
  f.t0 = 0, f.t1 = 1, f.u = ExposureTrajectory::virtual_times(int(frames.size() - 1) / 2);
  host_counts(ev, f, in);
  in.pairs = r.pairs;
  in.theta_pos = opt.theta_pos, in.theta_neg = opt.theta_neg, in.eps = opt.eps, in.norm_floor_rms = opt.norm_floor_rms;
  in.pool = pool;
  const double ref_value = reference::event_loss(in);
  INFO("gpu " << r.value << " reference " << ref_value);
  REQUIRE(std::abs(r.value - ref_value) <= 1e-4 * std::max(1.0, ref_value));

  // Central differences of the double reference at sampled (frame, element) entries.
  std::mt19937 rng(uint32_t(seed) + 5);
  double max_scale = 0;
  for (auto& g : r.grad)
    for (float v : g) max_scale = std::max(max_scale, double(std::abs(v)) / weight);
  int bad = 0, checked = 0;
  for (int k = 0; k < 80; ++k) {
    const size_t fi = rng() % frames.size(), e = rng() % frames[0].size();
    const double h = 1e-6, x0 = in.frames[fi][e];
    in.frames[fi][e] = x0 + h;
    const double lp = reference::event_loss(in);
    in.frames[fi][e] = x0 - h;
    const double lm = reference::event_loss(in);
    in.frames[fi][e] = x0;
    const double fd = (lp - lm) / (2 * h), gpu = double(r.grad[fi][e]) / weight;
    ++checked;
    if (std::abs(gpu - fd) > 2e-3 * std::abs(fd) + 1e-4 * max_scale) {
      ++bad;
      UNSCOPED_INFO("frame " << fi << " element " << e << ": gpu " << gpu << " fd " << fd);
    }
  }
  REQUIRE(checked == 80);
  REQUIRE(bad == 0);
  REQUIRE(max_scale > 0);
}

std::vector<std::vector<float>> random_frames(uint32_t w, uint32_t h, uint32_t F, uint32_t seed, bool identical) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.05f, 0.95f);
  std::vector<std::vector<float>> frames(F, std::vector<float>(size_t(3) * w * h));
  for (uint32_t i = 0; i < F; ++i)
    for (auto& v : frames[i]) v = u(rng);
  if (identical)
    for (uint32_t i = 1; i < F; ++i) frames[i] = frames[0];
  return frames;
}

}  // namespace

TEST_CASE("event loss pairs: t_s is drawn from t_0..t_i for every i, deterministically", "[events][loss]") {
  std::vector<int> seen(7, 0);
  for (uint64_t seed = 0; seed < 200; ++seed) {
    auto p = EventLoss::sample_pairs(7, seed);
    REQUIRE(p == EventLoss::sample_pairs(7, seed));
    REQUIRE(p.size() == 6);
    for (uint32_t i = 0; i < 6; ++i) {
      REQUIRE(p[i].second == i + 1);
      REQUIRE(p[i].first <= i);
      if (i == 5) seen[p[i].first]++;
    }
  }
  for (int s = 0; s < 6; ++s) CHECK(seen[s] > 10);  // every start time occurs
}

TEST_CASE("event loss value and frame gradients match the double reference (finite differences)", "[events][loss]") {
  const uint32_t W = 24, H = 16;
  auto ev = random_events(W, H, 4000, 3);
  SECTION("moving frames") { check_against_reference(ev, random_frames(W, H, 7, 11, false), 17); }
  SECTION("identical frames: the render-side norm sits on its floor") {
    check_against_reference(ev, random_frames(W, H, 7, 12, true), 18);
  }
  SECTION("five frames (N = 2)") { check_against_reference(ev, random_frames(W, H, 5, 13, false), 19); }
  SECTION("pooled over 5 x 5 cells, the last ones cut by the border") {
    check_against_reference(ev, random_frames(W, H, 7, 14, false), 20, 5);
  }
  SECTION("pooled over 2 x 2 cells") { check_against_reference(ev, random_frames(W, H, 5, 15, false), 21, 2); }
  // 24 x 16 pixels take every pair in one pass at pool 1 up to 9 frames; 23 x 15 (not a multiple
  // of 4), 11 frames and pooled cells the per-pair kernels (the routing: the test below).
  SECTION("nine frames (N = 4), the most one pass takes") {
    check_against_reference(ev, random_frames(W, H, 9, 23, false), 24);
  }
  SECTION("eleven frames (N = 5), a pass per pair") {
    check_against_reference(ev, random_frames(W, H, 11, 25, false), 26);
  }
  SECTION("per pixel over a pixel count that is not a multiple of 4") {
    check_against_reference(random_events(23, 15, 4000, 4), random_frames(23, 15, 7, 16, false), 22);
  }
  test::require_no_validation_messages();
}

namespace {

// Frame gradients through the event loss from a common starting gradient (the image terms'
// share), then to the sRGB renders: once as the trainer did it without the folded plumbing (the
// share copied into each frame's gradient, the term adding to it, train/colour_decode_bwd per
// frame) and once through LossTerms with grad_in and render_grad. Returns both renders'
// gradients, and whether LossTerms said the term wrote them.
struct FoldRun {
  std::vector<std::vector<float>> plain, folded;
  bool folded_rendered = false;
  std::vector<std::vector<float>> frame_grad_after;  // the folded run's frame gradients afterwards
};

FoldRun run_fold(uint32_t W, uint32_t H, uint32_t F, uint32_t pool, uint32_t seed) {
  auto& ctx = test::gpu_context();
  const size_t n = size_t(3) * W * H;
  const EventStream ev = random_events(W, H, 3000, seed);
  GpuEvents gev(ctx, ev, {EventWindow{0.0, 1.0}}, "test events");
  EventLossOptions opt;
  opt.pool = pool;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), g(-1.0f, 1.0f);
  std::vector<float> share(n), poison(n, 123.0f);
  for (auto& v : share) v = 0.05f * g(rng);
  gpu::Buffer share_buf(ctx, n * 4, "share");
  share_buf.write(share);
  std::vector<gpu::Buffer> render, linear, grad, out_plain, out_folded;
  for (uint32_t i = 0; i < F; ++i) {
    std::vector<float> x(n), y(n);
    for (size_t k = 0; k < n; ++k) x[k] = u(rng), y[k] = io::srgb_to_linear(x[k]);  // some below the knee
    render.emplace_back(ctx, n * 4, "render"), render.back().write(x);
    linear.emplace_back(ctx, n * 4, "linear"), linear.back().write(y);
    grad.emplace_back(ctx, n * 4, "frame_grad");
    out_plain.emplace_back(ctx, n * 4, "render_grad_plain");
    out_folded.emplace_back(ctx, n * 4, "render_grad_folded");
  }
  ExposureFrames f;
  f.width = W, f.height = H, f.t0 = 0.0, f.t1 = 1.0, f.seed = seed;
  f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&linear[i]), f.grad.push_back(&grad[i]);
  FoldRun r;
  {
    EventLoss loss(ctx, gev, 0.7f, opt);
    gpu::Commands cmd(ctx);
    for (uint32_t i = 0; i < F; ++i) cmd.copy(share_buf, grad[i], n * 4);
    loss.record(cmd, f);
    for (uint32_t i = 0; i < F; ++i)
      record_colour(cmd, shaderio::kColourDecodeBwd, n, render[i], grad[i], out_plain[i]);
    cmd.submit();
    for (uint32_t i = 0; i < F; ++i) r.plain.push_back(out_plain[i].read<float>(n));
  }
  LossTerms terms;
  terms.add(std::make_unique<EventLoss>(ctx, gev, 0.7f, opt));
  for (uint32_t i = 0; i < F; ++i) {
    grad[i].write(poison), out_folded[i].write(poison);
    f.grad_in.push_back(&share_buf), f.render_grad.push_back(&out_folded[i]);
  }
  gpu::Commands cmd(ctx);
  r.folded_rendered = terms.record_exposure_terms(cmd, f);
  if (!r.folded_rendered)  // the frames' gradients are in grad: the image model decodes them
    for (uint32_t i = 0; i < F; ++i)
      record_colour(cmd, shaderio::kColourDecodeBwd, n, render[i], grad[i], out_folded[i]);
  cmd.submit();
  for (uint32_t i = 0; i < F; ++i) {
    r.folded.push_back(out_folded[i].read<float>(n));
    r.frame_grad_after.push_back(grad[i].read<float>(n));
  }
  return r;
}

void require_close(const std::vector<std::vector<float>>& a, const std::vector<std::vector<float>>& b) {
  REQUIRE(a.size() == b.size());
  double max_abs = 0;
  for (auto& v : a)
    for (float x : v) max_abs = std::max(max_abs, double(std::abs(x)));
  REQUIRE(max_abs > 0);
  int bad = 0;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t k = 0; k < a[i].size(); ++k)
      if (std::abs(double(a[i][k]) - b[i][k]) > 1e-5 * std::abs(double(a[i][k])) + 1e-7 * max_abs) {
        if (++bad <= 5) UNSCOPED_INFO("frame " << i << " element " << k << ": " << a[i][k] << " against " << b[i][k]);
      }
  REQUIRE(bad == 0);
}

}  // namespace

TEST_CASE("event loss: the renders' gradients from a starting gradient in one pass equal copy, add and decode",
          "[events][loss]") {
  SECTION("one pass per pixel: the term writes the renders' gradients, the frame gradients stay untouched") {
    FoldRun r = run_fold(24, 16, 7, 1, 47);
    REQUIRE(r.folded_rendered);
    require_close(r.plain, r.folded);
    for (auto& g : r.frame_grad_after)
      for (float v : g) REQUIRE(v == 123.0f);
  }
  SECTION("nine frames: the renders' gradients where the device binds 20 texel buffers, else the image model's") {
    FoldRun r = run_fold(24, 16, 9, 1, 49);
    REQUIRE(r.folded_rendered == test::gpu_context().caps().fits_bindings(9, 20));
    require_close(r.plain, r.folded);
  }
  SECTION("pooled cells, a pass per pair: LossTerms copies the share first, the image model decodes") {
    FoldRun r = run_fold(24, 16, 5, 2, 50);
    REQUIRE_FALSE(r.folded_rendered);
    require_close(r.plain, r.folded);
  }
  test::require_no_validation_messages();
}

TEST_CASE("event loss: every pair in one pass per pixel up to 9 frames, a pass per pair otherwise", "[events][loss]") {
  auto& ctx = test::gpu_context();
  GpuEvents gev(ctx, random_events(24, 16, 100, 5), {EventWindow{0.0, 1.0}}, "test events");
  auto takes = [&](uint32_t w, uint32_t h, uint32_t F, uint32_t pool) {
    EventLossOptions opt;
    opt.pool = pool;
    EventLoss loss(ctx, gev, 1.0f, opt);
    ExposureFrames f;
    f.width = w, f.height = h;
    f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
    if (F % 2 == 0) f.u.resize(F, 1.0);
    return loss.takes_pairs_at_once(f);
  };
  CHECK(takes(24, 16, 7, 1));
  CHECK(takes(24, 16, 2, 1));
  CHECK(takes(24, 16, 9, 1));
  CHECK_FALSE(takes(24, 16, 11, 1));
  CHECK_FALSE(takes(23, 15, 7, 1));
  CHECK_FALSE(takes(24, 16, 7, 2));
}

TEST_CASE("event loss sign: renders that follow the simulator's events score near 0, the opposite convention near 4",
          "[events][loss]") {
  // A pattern drifting 10 px over the exposure, fed to the event simulator with exact
  // thresholds; the frames are the same pattern at the virtual times.
  const uint32_t W = 48, H = 32, F = 7;
  auto I = [](double x, double y, double t) {
    return 0.45 + 0.35 * std::sin(2 * M_PI * (x - 10.0 * t) / 14.0 + 0.2 * y) * std::cos(0.05 * (x + 10.0 * t));
  };
  events::EventSimulator sim(W, H, events::EventModelParams::ideal(), 5);
  std::vector<double> luma(size_t(W) * H);
  for (int s = 0; s <= 400; ++s) {
    const double t = s / 400.0;
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < W; ++x) luma[size_t(y) * W + x] = I(x + 0.5, y + 0.5, t);
    sim.add_frame(luma.data(), t);
  }
  EventStream ev = sim.take_events();
  REQUIRE(ev.size() > 2000);
  const auto u = ExposureTrajectory::virtual_times(3);
  std::vector<std::vector<float>> forward(F);
  for (uint32_t i = 0; i < F; ++i) {
    forward[i].resize(size_t(3) * W * H);
    for (uint32_t c = 0; c < 3; ++c)
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) forward[i][(size_t(c) * H + y) * W + x] = float(I(x + 0.5, y + 0.5, u[i]));
  }
  // The opposite convention (D = earlier minus later) is the same as flipping every polarity.
  EventStream flipped = ev;
  for (auto& p : flipped.p) p = int8_t(-p);
  EventLossOptions opt;  // thresholds 0.2 / 0.2 as the ideal simulator
  double fwd = 0, rev = 0;
  for (uint64_t seed = 0; seed < 4; ++seed) {
    fwd += run_gpu(ev, forward, opt, 1.0f, seed).value / 4;
    rev += run_gpu(flipped, forward, opt, 1.0f, seed).value / 4;
  }
  INFO("loss with the events as simulated " << fwd << ", with the opposite sign convention " << rev);
  CHECK(fwd < 0.3);  // cosine > 0.85 between events and log-luminance change
  CHECK(rev > 3.4);
  test::require_no_validation_messages();
}

// score_reversed_next: the time-reversed order's value, from the forward record's own pass over
// the counts (pool 1) or a value record of its own (pool 2), equals what record_value() writes
// for the reversed frames, and the forward order's value and gradients are the same as without it.
TEST_CASE("event loss: the reversed order scored beside the forward record equals a value record of it",
          "[events][loss]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 24, H = 16, F = 7;
  const GpuEvents gev(ctx, random_events(W, H, 6000, 41), {{0.0, 1.0}}, "test events");
  const auto frames = random_frames(W, H, F, 43, false);
  const size_t n = frames[0].size();
  std::vector<gpu::Buffer> rgb, grad;
  for (uint32_t i = 0; i < F; ++i) {
    rgb.emplace_back(ctx, n * 4, "frame");
    rgb.back().write(frames[i]);
    grad.emplace_back(ctx, n * 4, "frame_grad");
  }
  auto frames_of = [&](bool reversed, bool with_grad) {
    return exposure_of(rgb, with_grad ? &grad : nullptr, W, H, 0, {0.0, 1.0}, 47, reversed);
  };
  for (uint32_t pool : {1u, 2u}) {
    INFO("pool " << pool);
    EventLossOptions o;
    o.pool = pool;
    // The forward record alone, then the reversed order's value record.
    EventLoss plain(ctx, gev, 0.1f, o);
    gpu::Commands cmd(ctx);
    for (auto& g : grad) g.write(std::vector<float>(n, 0.5f));
    plain.record(cmd, frames_of(false, true));
    cmd.submit();
    const float forward = float(plain.value());
    std::vector<std::vector<float>> plain_grads;
    for (auto& g : grad) plain_grads.push_back(g.read<float>(n));
    plain.record_value(cmd, frames_of(true, false));
    cmd.submit();
    const float reversed = float(plain.value());
    REQUIRE(std::abs(forward - reversed) > 1e-3f);

    // Both from one record.
    EventLoss fused(ctx, gev, 0.1f, o);
    gpu::Buffer scores(ctx, 8, "scores");
    scores.write(std::vector<float>{-1.0f, -1.0f});
    for (auto& g : grad) g.write(std::vector<float>(n, 0.5f));
    fused.score_reversed_next(scores, 1);
    fused.record(cmd, frames_of(false, true));
    cmd.submit();
    const auto s = scores.read<float>(2);
    CHECK(s[0] == -1.0f);  // only the requested slot is written
    CHECK(s[1] == reversed);
    CHECK(float(fused.value()) == forward);
    for (uint32_t i = 0; i < F; ++i) CHECK(grad[i].read<float>(n) == plain_grads[i]);

    // One record only: the next leaves the slot alone.
    scores.write(std::vector<float>{-1.0f, -1.0f});
    fused.record(cmd, frames_of(false, true));
    cmd.submit();
    CHECK(scores.read<float>(2)[1] == -1.0f);
  }
  test::require_no_validation_messages();
}

TEST_CASE(
    "event loss: the value-only record matches the full one, and each view's counts are kept or shared past the cap",
    "[events][loss]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 24, H = 16, F = 7;
  auto ev = random_events(W, H, 6000, 21);
  const std::vector<EventWindow> windows{{0.0, 0.5}, {0.5, 1.0}};
  GpuEvents gev(ctx, ev, windows, "test events");
  auto frames = random_frames(W, H, F, 23, false);
  const size_t n = frames[0].size();
  std::vector<gpu::Buffer> rgb, grad;
  for (uint32_t i = 0; i < F; ++i) {
    rgb.emplace_back(ctx, n * 4, "frame");
    rgb.back().write(frames[i]);
    grad.emplace_back(ctx, n * 4, "frame_grad");
    grad.back().write(std::vector<float>(n, 0.0f));
  }
  auto frames_of = [&](uint32_t view, bool reversed, bool with_grad) {
    return exposure_of(rgb, with_grad ? &grad : nullptr, W, H, view, windows[view], 31, reversed);
  };
  // Each value from a fresh term: nothing cached.
  auto fresh_value = [&](uint32_t view, bool reversed) {
    EventLoss fresh(ctx, gev, 0.1f);
    gpu::Commands cmd(ctx);
    fresh.record(cmd, frames_of(view, reversed, true));
    cmd.submit();
    return fresh.value();
  };
  const double forward0 = fresh_value(0, false), reversed0 = fresh_value(0, true), forward1 = fresh_value(1, false);
  REQUIRE(std::abs(forward0 - reversed0) > 1e-3);  // the two orders score differently
  for (uint32_t i = 0; i < F; ++i) grad[i].write(std::vector<float>(n, 0.0f));

  EventLoss loss(ctx, gev, 0.1f);
  gpu::Commands cmd(ctx);
  loss.record_value(cmd, frames_of(0, true, false));  // as the trainer's direction check does
  cmd.submit();
  CHECK(loss.count_passes() == 1);
  CHECK(loss.value() == Approx(reversed0).epsilon(1e-6));
  for (uint32_t i = 0; i < F; ++i) {  // no gradient written
    auto g = grad[i].read<float>(n);
    REQUIRE(std::all_of(g.begin(), g.end(), [](float v) { return v == 0.0f; }));
  }
  loss.record(cmd, frames_of(0, false, true));  // same view and times: the counts are reused
  cmd.submit();
  CHECK(loss.count_passes() == 1);
  CHECK(loss.value() == Approx(forward0).epsilon(1e-6));
  loss.record(cmd, frames_of(1, false, true));  // another view: counted into its own planes
  cmd.submit();
  CHECK(loss.count_passes() == 2);
  CHECK(loss.value() == Approx(forward1).epsilon(1e-6));
  loss.record(cmd, frames_of(0, false, true));  // the first view again: its planes were kept
  cmd.submit();
  CHECK(loss.count_passes() == 2);
  CHECK(loss.value() == Approx(forward0).epsilon(1e-6));
  auto other = frames_of(0, false, true);
  other.u = ExposureTrajectory::virtual_times(2);  // other times (5 frames): counted again
  other.rgb.resize(5), other.grad.resize(5);
  loss.record(cmd, other);
  cmd.submit();
  CHECK(loss.count_passes() == 3);

  EventLossOptions small;  // no room to keep a view's planes: one shared set, counted per view change
  small.count_cache_bytes = 0;
  EventLoss shared(ctx, gev, 0.1f, small);
  const std::vector<std::pair<uint32_t, double>> visits{{0, forward0}, {0, forward0}, {1, forward1}, {0, forward0}};
  for (const auto& [view, expected] : visits) {
    shared.record(cmd, frames_of(view, false, true));
    cmd.submit();
    CHECK(shared.value() == Approx(expected).epsilon(1e-6));
  }
  CHECK(shared.count_passes() == 3);
  test::require_no_validation_messages();
}

TEST_CASE("event terms in training: event_weight_end fades them after the direction check, event_pool sums cells",
          "[events][train][gpu]") {
  namespace fs = std::filesystem;
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_event_schedule");
  std::string out;
  REQUIRE(test::run_evflow(dir,
                           "simulate --scene objects --out sim --width 40 --height 30 --seed 2 --train-views 3 "
                           "--novel-views 1",
                           out) == 0);
  auto train = [&](const std::string& run, const std::string& keys) {
    const std::string a = "train sim --out " + run +
                          " method=blur+events event_from=0 event_flip_until=0.5 iterations=10 init_gaussians=300 "
                          "max_gaussians=600 sh_degree=0 " +
                          keys;
    const int rc = test::run_evflow(dir, a, out);
    INFO(a << "\n" << out);
    REQUIRE(rc == 0);
    return plot::read_curve_csv(dir / run / "curve.csv");
  };
  // The logged total is l1_ssim + 0.1 * f(step) * events: f = 1 up to step 5, then 1 - 0.75 (s - 5) / 5.
  const plot::CurveTable t = train("fade", "event_weight_end=0.25");
  const int loss = t.column("loss"), image = t.column("l1_ssim"), events = t.column("events"), step = t.column("step");
  REQUIRE(t.rows.size() == 10);
  for (const auto& r : t.rows) {
    const double s = r[size_t(step)], f = s <= 5 ? 1.0 : 1.0 - 0.75 * (s - 5) / 5;
    INFO("step " << s);
    REQUIRE(r[size_t(events)] > 0.0);
    CHECK(r[size_t(loss)] == Approx(r[size_t(image)] + 0.1 * f * r[size_t(events)]).epsilon(1e-4));
  }
  // Pooled: a different event value on the same first step (the renders are the same), no lower
  // than 0 and below 4.
  const plot::CurveTable p1 = train("pool1", ""), p3 = train("pool3", "event_pool=3");
  const double e1 = p1.rows[0][size_t(events)], e3 = p3.rows[0][size_t(events)];
  INFO("first-step event loss per pixel " << e1 << ", over 3 x 3 cells " << e3);
  CHECK(p1.rows[0][size_t(image)] == p3.rows[0][size_t(image)]);
  CHECK(std::abs(e1 - e3) > 1e-3);
  CHECK(e3 > 0.0);
  CHECK(e3 < 4.0);
  CHECK(test::run_evflow(dir, "train sim --out bad2 method=blur+events event_pool=0 iterations=2", out) != 0);
  CHECK(out.find("pool must be in 1..64") != std::string::npos);
  fs::remove_all(dir);
}
