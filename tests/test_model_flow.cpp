// The model's flow (engine/train/model_flow.h, flow=model): the host maths against the
// simulator's ground-truth flow, the rendered depth of a plane of splats against the analytic
// flow of a known camera translation, and the trainer's use of it (each view's own poses).
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "camera/trajectory.h"
#include "gpu_fixture.h"
#include "sim/simulator.h"
#include "splat/synthetic.h"
#include "train/checkpoint.h"
#include "train/model_flow.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"

using namespace evflow;

namespace {

Camera pinhole(uint32_t W, uint32_t H, double f) {
  Camera c;
  c.width = W, c.height = H, c.fx = c.fy = f, c.cx = W / 2.0, c.cy = H / 2.0;
  c.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  c.t = {0, 0, 0};
  return c;
}

// A fronto-parallel plane z = Z of flat, nearly opaque grey splats on a grid of pitch `step`
// over |x| <= half_w, |y| <= half_h, with no splat in the square |x|, |y| < hole.
GaussianCloud splat_plane(double Z, double half_w, double half_h, double step, double hole) {
  GaussianCloud c;
  std::vector<std::array<float, 3>> pts;
  for (double y = -half_h; y <= half_h + 1e-9; y += step)
    for (double x = -half_w; x <= half_w + 1e-9; x += step)
      if (!(std::fabs(x) < hole && std::fabs(y) < hole)) pts.push_back({float(x), float(y), float(Z)});
  c.resize(pts.size(), 0);
  for (size_t i = 0; i < pts.size(); ++i) {
    for (int k = 0; k < 3; ++k) c.means[3 * i + k] = pts[i][k];
    c.log_scales[3 * i] = c.log_scales[3 * i + 1] = float(std::log(0.7 * step));
    c.log_scales[3 * i + 2] = float(std::log(1e-3));
    c.quats[4 * i] = 1, c.quats[4 * i + 1] = c.quats[4 * i + 2] = c.quats[4 * i + 3] = 0;
    c.opacity_logits[i] = 5.0f;
    for (int k = 0; k < 3; ++k) c.sh[3 * i + k] = 0.0f;
  }
  return c;
}

}  // namespace

TEST_CASE("model flow: depth lifted at camera a and projected at b is the simulator's ground-truth flow",
          "[flow][model]") {
  const uint32_t W = 40, H = 30;
  Camera a = pinhole(W, H, 35), b = pinhole(W, H, 35);
  // b: rotated a little about an oblique axis and moved.
  const double ang = 0.03, ax[3] = {0.3, 0.9, 0.3};
  const double n = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
  const double x = ax[0] / n, y = ax[1] / n, z = ax[2] / n, c = std::cos(ang), s = std::sin(ang), C = 1 - c;
  b.R = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, c + y * y * C,
         y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, c + z * z * C};
  b.t = {0.05, -0.02, 0.1};
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> depth_of(1.0f, 5.0f);
  std::vector<float> depth(size_t(W) * H), alpha(depth.size(), 1.0f);
  for (float& d : depth) d = depth_of(rng);
  alpha[7] = 0.49f;  // below the opacity floor: no flow
  const std::vector<float> mine = depth_flow(depth, alpha, a, b), truth = sim::ground_truth_flow(depth, a, b);
  REQUIRE(mine.size() == truth.size());
  CHECK(std::isnan(mine[14]));
  CHECK(std::isnan(mine[15]));
  double worst = 0;
  for (size_t i = 0; i < mine.size(); ++i)
    if (i / 2 != 7) worst = std::max(worst, double(std::fabs(mine[i] - truth[i])));
  CHECK(worst < 1e-4);
  // Identical cameras: no motion.
  double still = 0;
  for (float f : depth_flow(depth, std::vector<float>(depth.size(), 1.0f), a, a))
    still = std::max(still, double(std::fabs(f)));
  CHECK(still < 1e-5);
}

TEST_CASE("model flow: a rendered plane of splats moved past by a known translation gives the analytic flow",
          "[flow][model][gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 64, H = 48;
  const double f = 60, Z = 4;
  const GaussianCloud cloud = splat_plane(Z, 2.6, 2.0, 0.05, 0.4);
  GaussianBuffers params(ctx, cloud.size(), 0, "plane_");
  params.upload(cloud);
  // Camera b's centre is at (0.1, 0.05, 0.2): t_b = -R c.
  const Camera a = pinhole(W, H, f);
  Camera b = a;
  const double cb[3] = {0.1, 0.05, 0.2};
  b.t = {-cb[0], -cb[1], -cb[2]};
  Rasterizer raster(ctx);
  ModelFlow model(ctx);
  // Settings without depth, as training passes them: the flow asks for the depth it reads.
  RenderSettings settings;
  settings.depth = false;
  const std::vector<std::vector<float>> flows = model.intervals(raster, params, {a, b}, settings);
  REQUIRE(flows.size() == 1);
  const std::vector<float>& d = flows[0];
  // The plane's point at pixel (x, y) of a: X = ((x + 0.5 - cx) / f * Z, (y + 0.5 - cy) / f * Z, Z).
  double err = 0;
  size_t valid = 0, hole_nan = 0, hole = 0;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t p = size_t(y) * W + x;
      const double X = (x + 0.5 - a.cx) / f * Z, Y = (y + 0.5 - a.cy) / f * Z;
      const bool in_hole = std::fabs(X) < 0.25 && std::fabs(Y) < 0.25;  // well inside the hole
      if (in_hole) {
        ++hole;
        hole_nan += std::isnan(d[2 * p]) && std::isnan(d[2 * p + 1]);
        continue;
      }
      if (std::fabs(X) < 0.55 && std::fabs(Y) < 0.55) continue;  // the hole's soft rim
      const double u = f * (X - cb[0]) / (Z - cb[2]) + b.cx - (x + 0.5);
      const double v = f * (Y - cb[1]) / (Z - cb[2]) + b.cy - (y + 0.5);
      if (!std::isfinite(d[2 * p])) continue;
      ++valid;
      err += std::hypot(d[2 * p] - u, d[2 * p + 1] - v);
    }
  const size_t rim = size_t(W) * H - hole;
  WARN("valid " << valid << " of about " << rim << ", AEE " << err / double(std::max<size_t>(valid, 1)) << " px");
  CHECK(hole > 20);
  CHECK(hole_nan == hole);
  CHECK(valid > size_t(0.8 * double(rim)));
  CHECK(err / double(valid) < 0.05);  // the flow is 1.4 to 2.9 px long
  test::require_no_validation_messages();
}

namespace {

// Mean |F_a(x) - F_b(x + d(x))| over the pixels with a flow whose moved position lies inside the
// image (F planar, 3 x H x W; F_b sampled bilinearly). `sign` scales d (-1: the reversed flow).
double warp_error(const std::vector<float>& fa, const std::vector<float>& fb, const std::vector<float>& d, uint32_t W,
                  uint32_t H, double sign) {
  double sum = 0;
  size_t n = 0;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t p = size_t(y) * W + x;
      if (!std::isfinite(d[2 * p]) || !std::isfinite(d[2 * p + 1])) continue;
      const double sx = x + sign * d[2 * p], sy = y + sign * d[2 * p + 1];
      if (sx < 0 || sy < 0 || sx > W - 1.001 || sy > H - 1.001) continue;
      const uint32_t x0 = uint32_t(sx), y0 = uint32_t(sy);
      const double ax = sx - x0, ay = sy - y0;
      for (int c = 0; c < 3; ++c) {
        const float* b = &fb[size_t(c) * W * H];
        const double v = (1 - ay) * ((1 - ax) * b[y0 * W + x0] + ax * b[y0 * W + x0 + 1]) +
                         ay * ((1 - ax) * b[(y0 + 1) * W + x0] + ax * b[(y0 + 1) * W + x0 + 1]);
        sum += std::abs(fa[size_t(c) * W * H + p] - v);
      }
      ++n;
    }
  REQUIRE(n > W * H / 4);
  return sum / (3.0 * n);
}

}  // namespace

// The trainer's wiring of flow=model: each view's interval i flow must come from that view's own
// trajectory poses at t_i and t_{i+1}, in that order. Three views move differently during their
// exposures (sideways drift, vertical drift, yaw) over a frozen scene, so only the right poses
// carry the view's render at t_i onto its render at t_{i+1}; another view's flow, or the flow
// of the swapped pair, does not.
TEST_CASE("flow=model in training: each view's interval flow carries its render at t_i onto t_i+1",
          "[gpu][train][flow]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 96, H = 72;
  io::Dataset data = render_synthetic_dataset(ctx, W, H, 3, 0, 3000);
  TrainConfig cfg;
  cfg.mode = TrainMode::Blur;
  cfg.blur_upsample = 4;  // uses the flow at every step
  cfg.flow = FlowSource::Model;
  cfg.init_gaussians = 3000;
  cfg.sh_degree = 0;
  cfg.densify = false;
  cfg.iterations = 4;
  Checkpoint start;
  const Camera c0 = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  start.cloud = synthetic_cloud(42, 3000, 0, c0);  // the scene the views were rendered from
  const int axis[3] = {0, 1, 4};                   // drift x, drift y, yaw
  const double amp[3] = {0.5, 0.4, 0.1};
  for (int v = 0; v < 3; ++v) {
    TrajectoryState s;
    s.knots.assign(ExposureTrajectory::kSize, 0.0);
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) s.knots[j * 6 + axis[v]] = amp[v] * (j - 4) / 4.0;
    start.trajectories.push_back(s);
  }
  Trainer t(ctx, data, cfg, start);
  t.step();
  REQUIRE(t.model_flow_step() == 1);
  const uint32_t intervals = t.flow_intervals();
  REQUIRE(intervals == 6);
  for (uint32_t v = 0; v < 3; ++v)
    for (uint32_t i : {0u, 2u, 5u}) {
      const ViewSnapshot s = t.snapshot(v, int(i));
      const auto fa = s.frames[i]->read<float>(size_t(W) * H * 3), fb = s.frames[i + 1]->read<float>(size_t(W) * H * 3);
      const std::vector<float>& d = s.flow.flow;
      const std::vector<float> other = t.snapshot((v + 1) % 3, int(i)).flow.flow;
      const std::vector<float> zero(d.size(), 0.f);
      const double e = warp_error(fa, fb, d, W, H, 1), e0 = warp_error(fa, fb, zero, W, H, 1),
                   e_rev = warp_error(fa, fb, d, W, H, -1), e_other = warp_error(fa, fb, other, W, H, 1);
      INFO("view " << v << " interval " << i << ": warp error " << e << ", no flow " << e0 << ", reversed " << e_rev
                   << ", the next view's flow " << e_other);
      CHECK(e < 0.4 * e0);
      CHECK(e < 0.5 * e_rev);
      CHECK(e < 0.5 * e_other);
    }
  test::require_no_validation_messages();
}
