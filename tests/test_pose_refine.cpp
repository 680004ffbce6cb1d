// Pose refinement: test-pose refinement with frozen Gaussians (evaluation) and the trainer's
// per-view se(3) refinement in plain mode; blur + events training end to end.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "events/event_model.h"
#include "gpu_fixture.h"
#include "loss/event_loss.h"
#include "optim/schedule.h"
#include "splat/synthetic.h"
#include "train/checkpoint.h"
#include "train/pose_refine.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"

using namespace evflow;

namespace {

// Pixel coordinates of world point p.
std::array<double, 2> pixel_of(const Camera& c, const std::array<double, 3>& p) {
  std::array<double, 3> q = c.t;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) q[r] += c.R[r * 3 + k] * p[k];
  return {c.fx * q[0] / q[2] + c.cx, c.fy * q[1] / q[2] + c.cy};
}

double pose_error(const Camera& a, const Camera& b) {
  auto d = lie::se3_log(camera_to_world(a).inverse() * camera_to_world(b));
  double s = 0;
  for (double x : d) s += x * x;
  return std::sqrt(s);
}

// Exposure motion of the blur + events test: a sideways drift and a little yaw.
const double kDrift = 0.2, kYaw = 0.048;
const Camera kCam0 = Camera::look_at(96, 72, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});

// Four 96x72 views of a synthetic cloud, each blurred by the exposure motion kDrift / kYaw
// (knot j: (j - 4) / 4 of it) with ideal events rendered along the same motion.
io::Dataset drifting_views(gpu::Context& ctx, const GaussianCloud& truth) {
  io::Dataset data = render_synthetic_dataset(ctx, 96, 72, 4, 0);
  GaussianBuffers gt(ctx, truth.size(), 0, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  data.events.width = 96, data.events.height = 72;
  for (size_t v = 0; v < data.train.size(); ++v) {
    ExposureTrajectory motion(data.train[v].camera, 100 + v, 0.0);
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) {
      motion.data()[j * 6 + 0] = kDrift * (j - 4) / 4.0;
      motion.data()[j * 6 + 4] = kYaw * (j - 4) / 4.0;
    }
    const double t0 = 0.1 * v, T = 0.04;
    data.train[v].exposure_start = t0, data.train[v].exposure_end = t0 + T;
    events::EventSimulator sim(96, 72, events::EventModelParams::ideal(), 7 + v);
    std::vector<float> mean(96 * 72 * 3, 0.f), luma(96 * 72);
    const int sub = 48;
    for (int k = 0; k <= sub; ++k) {
      r.forward(gt, motion.camera_at(k / double(sub)), RenderSettings{}, rs);
      auto img = rs.outputs().rgb.read<float>(mean.size());
      for (float& x : img) x = io::srgb_to_linear(x);  // renders are sRGB; events and blur see linear light
      for (size_t i = 0; i < luma.size(); ++i)
        luma[i] = 0.2126f * img[i] + 0.7152f * img[luma.size() + i] + 0.0722f * img[2 * luma.size() + i];
      sim.add_frame(luma.data(), t0 + T * k / sub);
      for (size_t i = 0; i < mean.size(); ++i) mean[i] += img[i] / (sub + 1);
    }
    data.train[v].blurry = io::image_from_planar_rgb(mean, 96, 72);
    EventStream ev = sim.take_events();
    for (size_t i = 0; i < ev.size(); ++i) data.events.push(ev.x[i], ev.y[i], ev.t[i], ev.p[i]);
  }
  data.events.validate("test events");
  return data;
}

}  // namespace

TEST_CASE("refine_pose recovers a perturbed camera with the Gaussians frozen", "[gpu][train][camera]") {
  auto& ctx = test::gpu_context();
  GaussianCloud truth = synthetic_cloud(42, 1500, 0, kCam0);
  GaussianBuffers p(ctx, truth.size(), 0, "p_");
  p.upload(truth);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  r.forward(p, kCam0, RenderSettings{}, rs);
  gpu::Buffer target(ctx, 96 * 72 * 12, "target");
  target.write(rs.outputs().rgb.read<float>(96 * 72 * 3));
  const Camera start = kCam0.perturbed({0.03, -0.02, 0.02, 0.01, -0.015, 0.008});
  PoseRefineOptions o;
  o.iterations = 80;
  auto res = refine_pose(ctx, r, p, start, target, o);
  const double before = pose_error(kCam0, start), after = pose_error(kCam0, res.camera);
  std::printf("refine_pose: pose error %.4f -> %.4f, loss %.4f -> %.4f\n", before, after, res.first_loss,
              res.last_loss);
  REQUIRE(res.last_loss < 0.5 * res.first_loss);
  REQUIRE(after < 0.3 * before);
  test::require_no_validation_messages();
}

TEST_CASE("plain mode pose_refine: noisy training poses move towards the true ones and checkpoint",
          "[gpu][train][camera]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = render_synthetic_dataset(ctx, 96, 72, 4, 0);
  std::vector<Camera> truth_cams;
  const std::array<std::array<double, 6>, 4> noise = {{{0.02, -0.01, 0.0, 0.008, -0.01, 0.004},
                                                       {-0.015, 0.02, 0.01, -0.006, 0.008, 0.0},
                                                       {0.01, 0.015, -0.02, 0.0, 0.01, -0.006},
                                                       {-0.02, -0.01, 0.015, 0.01, 0.0, 0.008}}};
  for (size_t v = 0; v < 4; ++v) {
    truth_cams.push_back(data.train[v].camera);
    data.train[v].camera = data.train[v].camera.perturbed(noise[v]);
  }
  TrainConfig cfg;
  cfg.target = TrainTarget::Sharp;
  cfg.sh_degree = 0;
  cfg.densify = false;
  cfg.pose_refine = true;
  cfg.iterations = 160;
  cfg.lr_pose_init = 2e-3, cfg.lr_pose_final = 2e-4;
  // The Gaussians are the scene's own and (almost) frozen: only the poses can explain the images.
  cfg.lr_means_init = cfg.lr_means_final = 1e-12;
  cfg.lr_sh_dc = cfg.lr_sh_rest = cfg.lr_opacity = cfg.lr_log_scales = cfg.lr_quats = 1e-12;
  Checkpoint start{0, synthetic_cloud(42, 1500, 0, kCam0), {}};
  Trainer t(ctx, data, cfg, start);
  double before = 0, after = 0;
  for (size_t v = 0; v < 4; ++v) before += pose_error(truth_cams[v], t.training_camera(uint32_t(v))) / 4;
  while (t.current_step() < cfg.iterations) REQUIRE_FALSE(t.step().skipped);
  for (size_t v = 0; v < 4; ++v) after += pose_error(truth_cams[v], t.training_camera(uint32_t(v))) / 4;
  std::printf("pose_refine: mean pose error %.4f -> %.4f over %u steps\n", before, after, cfg.iterations);
  REQUIRE(after < 0.4 * before);
  auto path = std::filesystem::temp_directory_path() / "evf_pose.ckpt";
  write_checkpoint(path, t.checkpoint());
  Checkpoint c = read_checkpoint(path);
  REQUIRE(c.trajectories.size() == 4);
  REQUIRE(c.trajectories[0].knots.size() == 6);
  Trainer resumed(ctx, data, cfg, c);
  REQUIRE(pose_error(resumed.training_camera(2), t.training_camera(2)) == 0.0);
  std::filesystem::remove(path);
  test::require_no_validation_messages();
}

// The blur loss cannot tell a trajectory from its time reversal (same mean image); the events can.
TEST_CASE("blur+events: the event term tells the true exposure trajectory from its time reversal",
          "[gpu][train][events]") {
  auto& ctx = test::gpu_context();
  GaussianCloud truth = synthetic_cloud(42, 1500, 0, kCam0);
  io::Dataset data = drifting_views(ctx, truth);
  GaussianBuffers gt(ctx, truth.size(), 0, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  REQUIRE(data.events.size() > 1000);
  {
    // End to end: the event loss's gradient w.r.t. the trajectory knots (frame gradients ->
    // rasterizer pose gradients -> Bezier/Exp chain) against central differences.
    std::vector<EventWindow> wins;
    for (auto& v : data.train) wins.push_back({v.exposure_start, v.exposure_end});
    GpuEvents gev(ctx, data.events, wins, "test events");
    EventLoss el(ctx, gev, 1.0f);
    const auto us = ExposureTrajectory::virtual_times(3);
    const size_t n = 96 * 72 * 3;
    std::vector<gpu::Buffer> rgb, grad;
    for (size_t i = 0; i < us.size(); ++i) rgb.emplace_back(ctx, n * 4, "f"), grad.emplace_back(ctx, n * 4, "g");
    gpu::Buffer v_alpha(ctx, 96 * 72 * 4, "va");
    v_alpha.write(std::vector<float>(96 * 72, 0.f));
    GaussianBuffers grads(ctx, truth.size(), 0, "v_");
    auto loss_at = [&](const ExposureTrajectory& tr, std::array<double, ExposureTrajectory::kSize>* kg) {
      ExposureFrames f;
      f.view = 0, f.width = 96, f.height = 72, f.t0 = data.train[0].exposure_start, f.t1 = data.train[0].exposure_end;
      f.u = us, f.seed = 3;
      for (size_t i = 0; i < us.size(); ++i) {
        r.forward(gt, tr.camera_at(us[i]), RenderSettings{}, rs);
        rgb[i].write(rs.outputs().rgb.read<float>(n));
        grad[i].write(std::vector<float>(n, 0.f));
        f.rgb.push_back(&rgb[i]), f.grad.push_back(&grad[i]);
      }
      gpu::Commands cmd(ctx);
      el.record(cmd, f);
      cmd.submit();
      if (kg) {
        kg->fill(0.0);
        for (size_t i = 0; i < us.size(); ++i) {
          r.forward(gt, tr.camera_at(us[i]), RenderSettings{}, rs);
          r.backward(rs, gt, grad[i], v_alpha, grads, false);
          auto g = r.pose_gradient();
          auto k = tr.backward(us[i], lie::Vec6{g[0], g[1], g[2], g[3], g[4], g[5]});
          for (size_t j = 0; j < k.size(); ++j) (*kg)[j] += k[j];
        }
      }
      return el.value();
    };
    ExposureTrajectory tr(data.train[0].camera, 0, 0.0);
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j)
      tr.data()[j * 6 + 0] = 0.5 * kDrift * (j - 4) / 4.0, tr.data()[j * 6 + 4] = 0.5 * kYaw * (j - 4) / 4.0;
    std::array<double, ExposureTrajectory::kSize> kg{};
    loss_at(tr, &kg);
    const int comps[4] = {2 * 6 + 0, 6 * 6 + 0, 8 * 6 + 4, 0 * 6 + 1};
    for (int c : comps) {
      const double h = 2e-3, x0 = tr.data()[c];
      tr.data()[c] = x0 + h;
      const double lp = loss_at(tr, nullptr);
      tr.data()[c] = x0 - h;
      const double lm = loss_at(tr, nullptr);
      tr.data()[c] = x0;
      const double fd = (lp - lm) / (2 * h);
      std::printf("event loss knot gradient, component %d: analytic %.5g, central difference %.5g\n", c, kg[c], fd);
      INFO("knot component " << c);
      CHECK(kg[c] == Approx(fd).epsilon(0.03).margin(1e-3));  // 0.7-2.0 % apart here
    }
  }
  auto run = [&](double sign, bool flip = false) {
    TrainConfig cfg;
    cfg.apply_method("blur+events");
    cfg.event_flip_until = flip ? 1.0 : 0.0;
    cfg.event_from = 0.0;
    cfg.sh_degree = 0;
    cfg.iterations = 8;  // two steps per view, parameters frozen: this measures the terms
    cfg.densify = false;
    cfg.lr_trajectory_init = cfg.lr_trajectory_final = 1e-12;
    cfg.lr_means_init = cfg.lr_means_final = 1e-12;
    cfg.lr_sh_dc = cfg.lr_sh_rest = cfg.lr_opacity = cfg.lr_log_scales = cfg.lr_quats = 1e-12;
    Checkpoint init{0, truth, {}};
    for (size_t v = 0; v < data.train.size(); ++v) {
      TrajectoryState ts{0, std::vector<double>(54, 0.0), std::vector<double>(54, 0.0), std::vector<double>(54, 0.0)};
      for (int j = 0; j < 9; ++j)
        ts.knots[j * 6 + 0] = sign * kDrift * (j - 4) / 4.0, ts.knots[j * 6 + 4] = sign * kYaw * (j - 4) / 4.0;
      init.trajectories.push_back(ts);
    }
    Trainer t(ctx, data, cfg, init);
    REQUIRE(t.losses().size() == 2);
    REQUIRE(t.losses()[1]->name() == "events");
    std::array<double, 3> mean{0, 0, 0};
    while (t.current_step() < cfg.iterations) {
      auto st = t.step();
      if (st.step > 4) mean[2] += st.term_values[1] / (cfg.iterations - 4);  // after every view's first visit
      REQUIRE_FALSE(st.skipped);
      REQUIRE(st.term_values.size() == 2);
      REQUIRE(std::isfinite(st.term_values[1]));
      REQUIRE(st.term_values[1] >= 0.0);
      REQUIRE(st.term_values[1] <= 4.0);
      for (int k = 0; k < 2; ++k) mean[k] += st.term_values[k] / cfg.iterations;
    }
    if (flip) {
      // Every reversed trajectory was flipped on its view's first visit, back to the true knots.
      REQUIRE(t.trajectory_flips() == data.train.size());
      for (auto& tr : t.trajectories()) REQUIRE(tr.data()[8 * 6] == Approx(kDrift).margin(1e-9));
    }
    return mean;
  };
  auto fwd = run(1.0), rev = run(-1.0);
  std::printf("blur+events: true trajectory: blur %.5f events %.4f; time-reversed: blur %.5f events %.4f\n", fwd[0],
              fwd[1], rev[0], rev[1]);
  REQUIRE(std::abs(fwd[0] - rev[0]) < 0.25 * fwd[0]);  // the blur term barely sees the difference
  REQUIRE(fwd[1] < 0.6);                               // the events agree with the true motion
  REQUIRE(rev[1] > 2.0 * fwd[1]);                      // and not with its reversal
  // With the direction check on, the trainer turns the reversed trajectories around.
  auto fixed = run(-1.0, true);
  std::printf("blur+events: reversed start with the direction check: events %.4f after the flips\n", fixed[2]);
  REQUIRE(fixed[2] < 0.6);
  // Without events in the dataset the configuration is refused, naming the reason.
  io::Dataset no_events = data;
  no_events.events = EventStream{};
  TrainConfig cfg;
  cfg.apply_method("blur+events");
  REQUIRE_THROWS_WITH(Trainer(ctx, no_events, cfg), Catch::Contains("no events"));
  test::require_no_validation_messages();
}

// One training view, for the camera model alone (no images: nothing renders).
static io::Dataset one_view() {
  io::Dataset data;
  data.train.resize(1);
  data.train[0].camera = Camera::look_at(64, 48, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  return data;
}

// blur+events with an EDI warm-up over the first half of `iterations` steps.
static TrainConfig half_warmup(uint32_t iterations) {
  TrainConfig cfg;
  cfg.apply_method("blur+events");
  cfg.iterations = iterations;
  cfg.edi_warmup = 0.5;
  return cfg;
}

TEST_CASE("EDI warm-up: the mid-exposure pose gradient shifts a trajectory's knots together, keeping its motion",
          "[train][camera][warmup]") {
  const io::Dataset data = one_view();
  const TrainConfig cfg = half_warmup(10);
  CameraModel cameras(data, cfg);
  // A learned motion (drift and yaw growing along the exposure), so that each knot's own
  // gradient differs from the others' in more than scale.
  TrajectoryState s{0, std::vector<double>(ExposureTrajectory::kSize), std::vector<double>(ExposureTrajectory::kSize),
                    std::vector<double>(ExposureTrajectory::kSize)};
  for (int j = 0; j < ExposureTrajectory::kKnots; ++j)
    s.knots[j * 6 + 0] = kDrift * (j - 4) / 4.0, s.knots[j * 6 + 4] = 4 * kYaw * (j - 4) / 4.0,
                    s.knots[j * 6 + 2] = 0.1 * j * j / 16.0;
  cameras.load({s}, cfg);
  const std::vector<lie::Vec6> grads = {
      {0.3, -0.2, 0.1, 0.05, 0.4, -0.1}, {-0.9, 0.1, 0.3, -0.2, 0.1, 0.3}, {0.2, 0.5, -0.4, 0.3, -0.2, 0.1}};
  for (uint32_t step = 1; step <= grads.size(); ++step) cameras.shift_and_step(0, grads[step - 1], step);
  const double* k = cameras.trajectories()[0].data();
  double moved = 0;
  for (size_t i = 0; i < ExposureTrajectory::kSize; ++i) {
    const size_t c = i % ExposureTrajectory::kDof;
    moved = std::max(moved, std::abs(k[i] - s.knots[i]));
    CHECK(std::abs((k[i] - k[c]) - (s.knots[i] - s.knots[c])) <= 1e-12);
  }
  // Three Adam steps at the pose refinement's rate, 1e-3 decaying to 1e-5 over the 5 warm-up
  // steps (4.0e-4, 1.6e-4, 0.6e-4 at steps 1-3): a knot moves at most their sum.
  CHECK(moved > 1e-4);
  CHECK(moved <= 6.31e-4);
}

TEST_CASE("EDI warm-up: the knots' Adam moments start afresh at the first blur step", "[train][camera][warmup]") {
  const io::Dataset data = one_view();
  const TrainConfig cfg = half_warmup(1000);  // 500 warm-up steps, all of this one view's
  CameraModel cameras(data, cfg);
  // A converged warm-up: small shift gradients, so the moments' second moment is small.
  for (uint32_t step = 1; step <= 500; ++step) {
    cameras.begin_step(step);
    cameras.shift_and_step(0, {1e-4, -2e-4, 1e-4, 3e-5, -1e-4, 2e-5}, step);
  }
  REQUIRE(cameras.state()[0].step == 500);
  // The blur loss's first knot gradients are far larger. From fresh moments Adam's first step
  // moves each knot by the rate exactly; from the shift's it would move them about twice as far.
  const std::vector<double> before = cameras.state()[0].knots;
  const std::vector<lie::Vec6> frames(cameras.frame_times().size(), lie::Vec6{0.8, -0.5, 0.3, 0.2, -0.6, 0.4});
  cameras.begin_step(501);
  cameras.backward_and_step(0, frames, 501);
  const TrajectoryState after = cameras.state()[0];
  CHECK(after.step == 1);
  double moved = 0;
  for (size_t i = 0; i < before.size(); ++i) moved = std::max(moved, std::abs(after.knots[i] - before[i]));
  CHECK(moved > 0.9 * cfg.lr_trajectory_init);
  CHECK(moved <= cfg.lr_trajectory_init * (1 + 1e-9));
  // Only that step restarts them.
  cameras.begin_step(502);
  cameras.backward_and_step(0, frames, 502);
  CHECK(cameras.state()[0].step == 2);
}

// The largest difference between two poses' matrices and translations.
static double pose_gap(const lie::SE3& a, const lie::SE3& b) {
  double gap = 0;
  for (int i = 0; i < 9; ++i) gap = std::max(gap, std::abs(a.R[i] - b.R[i]));
  for (int i = 0; i < 3; ++i) gap = std::max(gap, std::abs(a.t[i] - b.t[i]));
  return gap;
}

TEST_CASE("EDI warm-up with edi_keep_mid: the blur steps learn the motion about the warm-up's mid-exposure pose",
          "[train][camera][warmup]") {
  const io::Dataset data = one_view();
  TrainConfig cfg = half_warmup(40);  // 20 warm-up steps, then 20 blur steps
  cfg.edi_keep_mid = true;
  CameraModel cameras(data, cfg);
  const std::vector<lie::Vec6> shift_grads = {{0.3, -0.2, 0.1, 0.05, 0.4, -0.1}, {-0.9, 0.1, 0.3, -0.2, 0.1, 0.3}};
  for (uint32_t step = 1; step <= 20; ++step) {
    cameras.begin_step(step);
    cameras.shift_and_step(0, shift_grads[step % 2], step);
  }
  // The warm-up moves the mid pose; keep_mid does not hold it there.
  const lie::SE3 mid = cameras.trajectories()[0].offset(0.5);
  CHECK(pose_gap(mid, lie::SE3::identity()) > 1e-3);
  // Frame gradients that would move the whole trajectory (each frame the same) and bend it
  // (growing along the exposure).
  std::vector<lie::Vec6> frames;
  for (size_t f = 0; f < cameras.frame_times().size(); ++f)
    frames.push_back({0.8 + 0.3 * f, -0.5, 0.3 * f, 0.2, -0.6 + 0.2 * f, 0.4});
  const ExposureTrajectory before = cameras.trajectories()[0];
  for (uint32_t step = 21; step <= 40; ++step) {
    cameras.begin_step(step);
    cameras.backward_and_step(0, frames, step);
  }
  const ExposureTrajectory& after = cameras.trajectories()[0];
  CHECK(pose_gap(after.offset(0.5), mid) < 1e-12);
  // Adam's moments hold no part that would move T(0.5): along the Bernstein weights at 0.5 the
  // first moment sums to zero in every component.
  const auto b = ExposureTrajectory::bernstein_weights(0.5);
  const std::vector<double> m = cameras.state()[0].exp_avg;
  for (int c = 0; c < ExposureTrajectory::kDof; ++c) {
    double along = 0, size = 0;
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) {
      along += b[j] * m[j * 6 + c];
      size = std::max(size, std::abs(m[j * 6 + c]));
    }
    CHECK(size > 0);
    CHECK(std::abs(along) < 1e-12 * size);
  }
  // The motion itself was learned: the exposure's ends moved apart, by tens of Adam steps.
  CHECK(pose_gap(after.offset(0.0), before.offset(0.0)) > 0.02);
  CHECK(pose_gap(after.offset(1.0), before.offset(1.0)) > 0.02);
  // Without the key the same steps move the mid pose too.
  cfg.edi_keep_mid = false;
  CameraModel free(data, cfg);
  for (uint32_t step = 1; step <= 20; ++step) free.shift_and_step(0, shift_grads[step % 2], step);
  for (uint32_t step = 21; step <= 40; ++step) {
    free.begin_step(step);
    free.backward_and_step(0, frames, step);
  }
  CHECK(pose_gap(free.trajectories()[0].offset(0.5), mid) > 0.02);
}

TEST_CASE("EDI warm-up with edi_mid_lr: the kept mid-exposure pose moves by its own slow Adam, resumable",
          "[train][camera][warmup]") {
  const io::Dataset data = one_view();
  TrainConfig cfg = half_warmup(40);  // 20 warm-up steps, then 20 blur steps
  cfg.edi_keep_mid = true;
  cfg.edi_mid_lr = 2e-4;
  CameraModel cameras(data, cfg);
  for (uint32_t step = 1; step <= 20; ++step) cameras.shift_and_step(0, {0.3, -0.2, 0.1, 0.05, 0.4, -0.1}, step);
  const lie::SE3 mid = cameras.trajectories()[0].offset(0.5);
  // Every frame pushed the same way: the whole trajectory would shift, so the part along the
  // Bernstein weights keeps its sign in every component, and Adam's normalised steps are the
  // rate, decayed as the knots' rate is, each against that sign.
  const lie::Vec6 push{0.8, -0.5, 0.3, 0.2, -0.6, 0.4};
  const std::vector<lie::Vec6> frames(cameras.frame_times().size(), push);
  auto blur_steps = [&](CameraModel& m, uint32_t from, uint32_t to) {
    for (uint32_t step = from; step <= to; ++step) {
      m.begin_step(step);
      m.backward_and_step(0, frames, step);
    }
  };
  blur_steps(cameras, 21, 30);
  const ExponentialDecay knots{cfg.lr_trajectory_init, cfg.lr_trajectory_final, 20};
  double travel = 0;  // the sum of the mid pose's rates over the ten steps
  for (uint32_t k = 1; k <= 10; ++k) travel += cfg.edi_mid_lr * knots(k) / cfg.lr_trajectory_init;
  const lie::Vec6 moved = lie::se3_log(mid.inverse() * cameras.trajectories()[0].offset(0.5));
  for (int c = 0; c < 6; ++c) {
    INFO("component " << c);
    CHECK(moved[c] == Approx(-travel * (push[c] > 0 ? 1 : -1)).epsilon(0.02));
  }
  const TrajectoryState saved = cameras.state()[0];
  CHECK(saved.mid_step == 10);
  REQUIRE(saved.mid_exp_avg.size() == 6);
  // Resumed from its state (through a checkpoint file), a model continues as the one that ran on.
  const std::filesystem::path dir = test::fresh_dir("evf_mid_lr");
  Checkpoint ck;
  ck.cloud.resize(0, 0);
  ck.trajectories = cameras.state();
  write_checkpoint(dir / "c.ckpt", ck);
  CameraModel resumed(data, cfg);
  resumed.load(read_checkpoint(dir / "c.ckpt").trajectories, cfg);
  blur_steps(cameras, 31, 40);
  blur_steps(resumed, 31, 40);
  CHECK(resumed.state()[0].knots == cameras.state()[0].knots);
  CHECK(resumed.state()[0].mid_exp_avg_sq == cameras.state()[0].mid_exp_avg_sq);
  // A model that does not move the mid pose drops the moments; one that does and finds none
  // starts them afresh.
  cfg.edi_mid_lr = 0;
  CameraModel held(data, cfg);
  held.load({saved}, cfg);
  CHECK(held.state()[0].mid_exp_avg.empty());
  cfg.edi_mid_lr = 2e-4;
  TrajectoryState old = saved;
  old.mid_exp_avg.clear(), old.mid_exp_avg_sq.clear();
  CameraModel fresh(data, cfg);
  fresh.load({old}, cfg);
  CHECK(fresh.state()[0].mid_step == 0);
  CHECK(fresh.state()[0].mid_exp_avg == std::vector<double>(6, 0.0));
  std::filesystem::remove_all(dir);
}

TEST_CASE("EDI warm-up with edi_warmup_motion: the knots learn the exposure's motion and its direction",
          "[gpu][train][camera][warmup]") {
  auto& ctx = test::gpu_context();
  GaussianCloud truth = synthetic_cloud(42, 1500, 0, kCam0);
  const io::Dataset data = drifting_views(ctx, truth);
  // Warm-up steps only, the Gaussians frozen at the truth: what moves is the knots. With
  // edi_warmup_motion = 1 every warm-up step fits a virtual frame; with 0 the mid-exposure one.
  auto warm_up = [&](bool motion) {
    TrainConfig cfg;
    cfg.apply_method("blur+events");
    cfg.sh_degree = 0;
    cfg.densify = false;
    cfg.iterations = 321;
    cfg.edi_warmup = 0.998;  // 320 warm-up steps, 80 per view
    cfg.edi_warmup_motion = motion ? 1.0 : 0.0;
    cfg.lr_trajectory_init = 2e-2, cfg.lr_trajectory_final = 2e-3;
    cfg.lr_means_init = cfg.lr_means_final = 1e-12;
    cfg.lr_sh_dc = cfg.lr_sh_rest = cfg.lr_opacity = cfg.lr_log_scales = cfg.lr_quats = 1e-12;
    Trainer t(ctx, data, cfg, Checkpoint{0, truth, {}});
    while (t.current_step() < cfg.edi_warmup_steps()) REQUIRE_FALSE(t.step().skipped);
    return t.trajectories();
  };
  // Where the scene's points move in the image over the exposure, as a learned trajectory says
  // and as the true one (knot 0 at -kDrift, -kYaw to knot 8 at +kDrift, +kYaw) does: the mean
  // endpoint error in pixels. Drift and yaw move the image alike, so poses are compared here.
  auto image_motion_error = [&](const ExposureTrajectory& learned, size_t v) {
    ExposureTrajectory real(data.train[v].camera, 0, 0.0);
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j)
      real.data()[j * 6 + 0] = kDrift * (j - 4) / 4.0, real.data()[j * 6 + 4] = kYaw * (j - 4) / 4.0;
    double err = 0, moved = 0;
    for (size_t g = 0; g < truth.size(); ++g) {
      const std::array<double, 3> p{truth.means[3 * g], truth.means[3 * g + 1], truth.means[3 * g + 2]};
      const auto flow = [&](const ExposureTrajectory& tr) {
        const auto a = pixel_of(tr.camera_at(0.0), p), b = pixel_of(tr.camera_at(1.0), p);
        return std::array<double, 2>{b[0] - a[0], b[1] - a[1]};
      };
      const auto fl = flow(learned), fr = flow(real);
      err += std::hypot(fl[0] - fr[0], fl[1] - fr[1]) / truth.size();
      moved += std::hypot(fr[0], fr[1]) / truth.size();
    }
    std::printf("view %zu: true image motion %.2f px, learned trajectory's endpoint error %.2f px\n", v, moved, err);
    return std::pair{err, moved};
  };
  const auto learned = warm_up(true), shifted = warm_up(false);
  for (size_t v = 0; v < data.train.size(); ++v) {
    const auto [err, moved] = image_motion_error(learned[v], v);
    CHECK(moved > 3.0);
    CHECK(err < 0.2 * moved);
    // The mid-exposure warm-up shifts the trajectories as a whole: no motion is learned.
    CHECK(image_motion_error(shifted[v], v).first > 0.9 * moved);
  }
  test::require_no_validation_messages();
}
