// The trainer's own wiring, end to end: the gradient one whole Trainer step applies (blur mean
// of 2N+1 sRGB renders decoded to linear light, the sRGB loss space, the event term on the
// linear frames, the rasterizer's backward, the trajectory chain) against central differences
// of that step's total loss.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "camera/trajectory.h"
#include "events/event_model.h"
#include "exposure_sim.h"
#include "gpu_fixture.h"
#include "splat/synthetic.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"

using namespace evflow;

namespace {

constexpr uint32_t W = 128, H = 96;
constexpr double kDrift = 0.15, kYaw = 0.03;
// A grey background: the event term's log intensity stays away from black, where the
// rasterizer's alpha cut-off (a Gaussian's edge at 1/255) makes the loss step, not slope.
constexpr float kGrey = 0.35f;

std::vector<double> motion_knots(double scale) {
  std::vector<double> k(ExposureTrajectory::kSize, 0.0);
  for (int j = 0; j < ExposureTrajectory::kKnots; ++j)
    k[j * 6 + 0] = scale * kDrift * (j - 4) / 4.0, k[j * 6 + 4] = scale * kYaw * (j - 4) / 4.0;
  return k;
}

// Four views whose blurry images and events come from the true cloud moving along known
// exposure trajectories (sRGB renders decoded to linear light, as the simulator's images are).
io::Dataset blur_event_dataset(gpu::Context& ctx, const GaussianCloud& truth) {
  io::Dataset data = render_synthetic_dataset(ctx, W, H, 4, 0, truth.size());
  GaussianBuffers gt(ctx, truth.size(), truth.sh_degree, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  RenderState state(ctx);
  data.events.width = W, data.events.height = H;
  for (size_t v = 0; v < data.train.size(); ++v) {
    ExposureTrajectory motion(data.train[v].camera, 0, 0.0);
    const auto k = motion_knots(1.0);
    std::copy(k.begin(), k.end(), motion.data());
    test::simulate_exposure(r, state, gt, data, v, motion, 0.1 * v, 0.04, 32, 11 + v, kGrey);
  }
  data.events.validate("test events");
  return data;
}

// Indices of the n largest |g|.
std::vector<size_t> largest(const std::vector<double>& g, size_t n) {
  std::vector<size_t> idx(g.size());
  std::iota(idx.begin(), idx.end(), size_t(0));
  std::partial_sort(idx.begin(), idx.begin() + n, idx.end(),
                    [&](size_t a, size_t b) { return std::abs(g[a]) > std::abs(g[b]); });
  idx.resize(n);
  return idx;
}

// The true scene: n random Gaussians in front of the views' camera.
GaussianCloud true_cloud(uint32_t n) {
  const Camera cam0 = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  return synthetic_cloud(42, n, 0, cam0);
}

// blur+events from the first step, no direction check (a step's update is its gradient), SH 0,
// the grey background, no density control.
TrainConfig step_config(uint32_t iterations) {
  TrainConfig cfg;
  cfg.apply_method("blur+events");
  cfg.virtual_frames = 3;
  cfg.sh_degree = 0;
  cfg.background = {kGrey, kGrey, kGrey};
  cfg.densify = false;
  cfg.iterations = iterations;
  cfg.event_from = 0.0;
  cfg.event_flip_until = 0.0;
  return cfg;
}

// A start away from the truth: colours off, trajectories at 60% of the motion.
Checkpoint perturbed_start(const GaussianCloud& truth, size_t views) {
  Checkpoint start{0, truth, {}};
  for (size_t i = 0; i < start.cloud.sh.size(); ++i) start.cloud.sh[i] += 0.3f * float((i % 7) / 6.0 - 0.5);
  for (size_t v = 0; v < views; ++v)
    start.trajectories.push_back({0, motion_knots(0.6), std::vector<double>(54, 0.0), std::vector<double>(54, 0.0)});
  return start;
}

}  // namespace

TEST_CASE("trainer: one step's applied gradient (blur + events, 2N+1 frames) matches central differences of its loss",
          "[gpu][train][gradient]") {
  auto& ctx = test::gpu_context();
  const GaussianCloud truth = true_cloud(300);
  const io::Dataset data = blur_event_dataset(ctx, truth);
  REQUIRE(data.events.size() > 500);

  const TrainConfig cfg = step_config(100);
  const Checkpoint start = perturbed_start(truth, data.train.size());

  Trainer t(ctx, data, cfg, start);
  const StepStats st = t.step();
  REQUIRE_FALSE(st.skipped);
  REQUIRE(st.term_values.size() == 2);
  REQUIRE(st.term_values[1] > 0.0);  // the event term took part
  const GaussianCloud g = t.last_gradients();
  const std::vector<double> kg = t.last_camera_gradient();
  REQUIRE(kg.size() == size_t(ExposureTrajectory::kSize));

  // The loss of the same first step from a perturbed start.
  auto loss_with = [&](const std::function<void(Checkpoint&)>& perturb) {
    Checkpoint c = start;
    perturb(c);
    Trainer p(ctx, data, cfg, c);
    const StepStats s = p.step();
    REQUIRE(s.view == st.view);
    return s.loss;
  };
  int checked = 0;
  auto check = [&](const char* what, size_t index, double analytic, double h,
                   const std::function<void(Checkpoint&, double)>& add) {
    // The least-squares slope of symmetric differences at +-h .. +-4h: the loss steps where a
    // Gaussian's edge crosses the 1/255 alpha cut-off and where an L1 residual changes sign, so a
    // single central difference scatters by a few percent; the fit follows the smooth slope.
    double num = 0, den = 0;
    for (int k = 1; k <= 4; ++k) {
      const double lp = loss_with([&](Checkpoint&c) { add(c, +k * h); }),
                   lm = loss_with([&](Checkpoint&c) { add(c, -k * h); });
      num += k * (lp - lm);
      den += 2.0 * k * k * h;
    }
    const double fd = num / den;
    std::printf("step gradient %s[%zu]: applied %.6g, central difference %.6g\n", what, index, analytic, fd);
    CHECK(std::abs(analytic - fd) <= 1e-2 * std::abs(fd));
    ++checked;
  };
  // Knots of the step's view.
  for (size_t k : largest(kg, 3))
    check("knot", k, kg[k], 1e-3, [&](Checkpoint& c, double d) { c.trajectories[st.view].knots[k] += d; });
  // Gaussian means, colours (SH DC) and opacities with the largest gradients.
  auto as_double = [](const std::vector<float>& f) { return std::vector<double>(f.begin(), f.end()); };
  const auto gm = as_double(g.means), gs = as_double(g.sh), go = as_double(g.opacity_logits);
  for (size_t i : largest(gm, 2))
    check("mean", i, gm[i], 2e-3, [&](Checkpoint& c, double d) { c.cloud.means[i] += float(d); });
  for (size_t i : largest(gs, 2))
    check("sh", i, gs[i], 1e-2, [&](Checkpoint& c, double d) { c.cloud.sh[i] += float(d); });
  for (size_t i : largest(go, 2))
    check("opacity", i, go[i], 1e-2, [&](Checkpoint& c, double d) { c.cloud.opacity_logits[i] += float(d); });
  REQUIRE(checked == 9);
  test::require_no_validation_messages();
}

TEST_CASE("trainer: an EDI warm-up step is the EDI baseline's step at the trajectory's mid-exposure pose",
          "[gpu][train][warmup]") {
  auto& ctx = test::gpu_context();
  const GaussianCloud truth = true_cloud(300);
  const io::Dataset data = blur_event_dataset(ctx, truth);

  TrainConfig cfg = step_config(6);
  cfg.edi_warmup = 0.5;  // steps 1-3
  cfg.event_from = 0.5;  // of the 3 blur steps: the event term from step 5
  const Checkpoint start = perturbed_start(truth, data.train.size());
  Trainer warm(ctx, data, cfg, start);

  // The baseline: plain mode on EDI targets, each view's camera the trajectory's mid-exposure one.
  io::Dataset mid = data;
  for (size_t v = 0; v < mid.train.size(); ++v) mid.train[v].camera = warm.training_camera(uint32_t(v));
  TrainConfig edi = cfg;
  edi.apply_method("edi");
  edi.edi_warmup = 0;
  Trainer baseline(ctx, mid, edi, Checkpoint{0, start.cloud, {}});

  const StepStats a = warm.step(), b = baseline.step();
  REQUIRE(a.view == b.view);
  REQUIRE_FALSE(a.skipped);
  CHECK(a.term_values.at(1) == 0.0);  // no event term in a warm-up step
  const double tol = test::bit_reproducible() ? 0.0 : 1e-5 * std::abs(b.loss);
  CHECK(std::abs(a.loss - b.loss) <= tol);
  const GaussianCloud ga = warm.last_gradients(), gb = baseline.last_gradients();
  CHECK(test::same_values(ga.means, gb.means));
  CHECK(test::same_values(ga.sh, gb.sh));
  CHECK(test::same_values(ga.opacity_logits, gb.opacity_logits));
  // The mid-exposure pose gradient shifts the view's knots together: the motion (each knot
  // less knot 0) stays as it was.
  const std::vector<double>& kg = warm.last_camera_gradient();
  REQUIRE(kg.size() == size_t(ExposureTrajectory::kSize));
  CHECK(std::any_of(kg.begin(), kg.end(), [](double x) { return x != 0.0; }));
  const double* after = warm.trajectories()[a.view].data();
  const std::vector<double>& before = start.trajectories[a.view].knots;
  double moved = 0;
  for (size_t k = 0; k < kg.size(); ++k) {
    const size_t c = k % ExposureTrajectory::kDof;
    moved = std::max(moved, std::abs(after[k] - before[k]));
    CHECK(std::abs((after[k] - after[c]) - (before[k] - before[c])) <= 1e-12);
  }
  CHECK(moved > 0.0);

  warm.step();
  warm.step();
  const StepStats c = warm.step(), d = warm.step();  // steps 4 and 5: the blur model
  CHECK(c.term_values.at(1) == 0.0);
  CHECK(d.term_values.at(1) > 0.0);
  test::require_no_validation_messages();
}

TEST_CASE("trainer: EDI warm-up settings that cannot work are refused, naming the conflict", "[gpu][train][warmup]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = blur_event_dataset(ctx, true_cloud(100));
  auto refused = [&](const std::function<void(TrainConfig&)>& set, const std::string& says) {
    TrainConfig cfg;
    cfg.apply_method("blur+events");
    cfg.iterations = 4;
    cfg.edi_warmup = 0.5;
    set(cfg);
    try {
      Trainer t(ctx, data, cfg);
      FAIL("accepted");
    } catch (const std::invalid_argument& e) { CHECK_THAT(e.what(), Catch::Contains(says)); }
  };
  refused([](TrainConfig& c) { c.edi_warmup = 1.0; }, "edi_warmup must be in [0, 1)");
  refused([](TrainConfig& c) { c.edi_warmup = -0.1; }, "edi_warmup must be in [0, 1)");
  refused([](TrainConfig& c) { c.apply_method("edi"), c.edi_warmup = 0.5; }, "needs mode=blur");
  refused([](TrainConfig& c) { c.edi_warmup_motion = 1.5; }, "edi_warmup_motion must be in [0, 1]");
  refused([](TrainConfig& c) { c.edi_warmup_motion = -0.5; }, "edi_warmup_motion must be in [0, 1]");
  refused([](TrainConfig& c) { c.edi_warmup = 0, c.edi_warmup_motion = 0.2; }, "needs edi_warmup > 0");
  refused([](TrainConfig& c) { c.edi_warmup = 0, c.edi_keep_mid = true; }, "edi_keep_mid keeps the mid pose");
  refused([](TrainConfig& c) { c.edi_warmup = 0.5, c.edi_mid_lr = 1e-4; }, "needs edi_keep_mid=true");
  io::Dataset no_events = data;
  no_events.events = {};
  TrainConfig cfg;
  cfg.apply_method("blur-only");
  cfg.edi_warmup = 0.5;
  CHECK_THROWS_WITH(Trainer(ctx, no_events, cfg), Catch::Contains("needs an event stream"));
}

TEST_CASE("trainer: with splats_from, the first blur steps train the knots alone, the later ones the Gaussians too",
          "[gpu][train][warmup]") {
  auto& ctx = test::gpu_context();
  const GaussianCloud truth = true_cloud(100);
  const io::Dataset data = blur_event_dataset(ctx, truth);
  TrainConfig cfg = step_config(16);
  cfg.edi_warmup = 0.25;  // steps 1-4
  cfg.splats_from = 0.5;  // of the 12 blur steps: 5-10 the knots alone, 11-16 everything
  const Checkpoint start = perturbed_start(truth, data.train.size());
  Trainer t(ctx, data, cfg, start);
  GaussianCloud before = t.cloud();
  while (t.current_step() < 16) {
    std::vector<double> knots_before;
    const uint32_t view = view_for_step(t.current_step() + 1, data.train.size(), cfg.seed);
    knots_before.assign(t.trajectories()[view].data(), t.trajectories()[view].data() + ExposureTrajectory::kSize);
    REQUIRE_FALSE(t.step().skipped);
    const GaussianCloud after = t.cloud();
    const bool knots_moved = !std::equal(knots_before.begin(), knots_before.end(), t.trajectories()[view].data());
    INFO("step " << t.current_step());
    CHECK(knots_moved);
    CHECK((after.sh != before.sh) == (t.current_step() <= 4 || t.current_step() > 10));
    before = after;
  }
  cfg.splats_from = 1.0;
  CHECK_THROWS_WITH(Trainer(ctx, data, cfg, start), Catch::Contains("splats_from must be in [0, 1)"));
  cfg.splats_from = 0.5;
  cfg.mode = TrainMode::Plain, cfg.edi_warmup = 0, cfg.event_weight = 0;
  CHECK_THROWS_WITH(Trainer(ctx, data, cfg, start), Catch::Contains("splats_from > 0 needs mode=blur"));
  test::require_no_validation_messages();
}
