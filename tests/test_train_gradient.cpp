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

}  // namespace

TEST_CASE("trainer: one step's applied gradient (blur + events, 2N+1 frames) matches central differences of its loss",
          "[gpu][train][gradient]") {
  auto& ctx = test::gpu_context();
  const Camera cam0 = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  const GaussianCloud truth = synthetic_cloud(42, 300, 0, cam0);
  const io::Dataset data = blur_event_dataset(ctx, truth);
  REQUIRE(data.events.size() > 500);

  TrainConfig cfg;
  cfg.apply_method("blur+events");
  cfg.virtual_frames = 3;
  cfg.sh_degree = 0;
  cfg.background = {kGrey, kGrey, kGrey};
  cfg.densify = false;
  cfg.iterations = 100;
  cfg.event_from = 0.0;        // the event term on from the first step
  cfg.event_flip_until = 0.0;  // no direction check: the step's update is its gradient
  // Start away from the truth: colours off, trajectories at 60% of the motion.
  Checkpoint start{0, truth, {}};
  for (size_t i = 0; i < start.cloud.sh.size(); ++i) start.cloud.sh[i] += 0.3f * float((i % 7) / 6.0 - 0.5);
  for (size_t v = 0; v < data.train.size(); ++v)
    start.trajectories.push_back({0, motion_knots(0.6), std::vector<double>(54, 0.0), std::vector<double>(54, 0.0)});

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
