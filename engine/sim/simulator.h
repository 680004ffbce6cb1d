// The event-camera blur dataset simulator (`evflow simulate`).
//
// Rig: `train_views` cameras on an arc around the scene's target, `novel_views` cameras between
// them (different heights/radii), all looking at the target. Each training view v has an
// exposure window [t0, t1] = [v * view_spacing_s, v * view_spacing_s + exposure_s] with a smooth,
// non-uniform 6-DoF shake: c2w(s) = c2w_mid * Exp(k * g(s)), s in [0, 1], g a sum of random
// sinusoids per degree of freedom (with `shake = jerk`, plus a sudden change of velocity each)
// with g(0.5) = 0, so the mid-exposure pose is the view's
// ground-truth pose. k is chosen so that the mean (over pixels) length of a pixel's image path
// during the exposure is `blur_px`.
// Sub-frames: times planned on a fine grid so that no pixel (of a grid of the mid-frame's
// surface points plus the border) moves more than `plan_step_px` between samples; s = 0.5 is
// always a sample. While rendering, the ground-truth flow of each interval (every pixel, from
// its depth and the two poses) is checked and an interval whose largest motion exceeds
// `max_step_px` is split, so the bound holds for every rendered pixel.
// Blurry image = time integral (trapezoid) of the linear sub-frames / exposure; ground truth =
// the sharp sub-frame at s = 0.5. Events: an EventSimulator per view fed with every sub-frame
// (linear RGB -> luma), seed = seed + view; the per-view streams are concatenated.
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>
#include "metrics/srgb_metrics.h"

#include <nlohmann/json.hpp>

#include "camera/camera.h"
#include "events/event_model.h"
#include "gpu/context.h"
#include "sim/mesh_renderer.h"
#include "sim/scene.h"

namespace evflow::sim {

struct SimParams {
  uint32_t width = 346, height = 260;
  double fov_y_deg = 50;
  int train_views = 16;
  int novel_views = 8;
  double arc_deg = 50;             // angular span of the training cameras around the target
  double exposure_s = 0.04;        // exposure window of a training view
  double view_spacing_s = 0.1;     // start-to-start time between training views
  double blur_px = 12;             // target mean pixel path length during an exposure
  double translation_share = 0.3;  // translation shake amplitude per unit of rotation, times the target distance
  // "smooth": the sinusoids alone; "jerk": plus, per degree of freedom, a sudden change of
  // velocity (a softplus ramp 0.01 of the exposure wide at a random time in [0.2, 0.8]).
  std::string shake = "smooth";
  double max_step_px = 0.5;       // hard bound on any pixel's motion between sub-frames
  double plan_step_px = 0.4;      // planning bound (on sampled points) before the hard check
  int max_subframes = 2000;       // per view; exceeding it is an error (blur too large)
  double pose_noise_rot_deg = 0;  // std dev of the recorded poses' rotation noise
  double pose_noise_trans = 0;    // std dev of the recorded poses' translation noise (scene units)
  uint64_t seed = 1;
  events::EventModelParams events = events::EventModelParams::defaults();
  ShadingParams shading;
  nlohmann::json to_json() const;
};

// Ground-truth flow from frame a to frame b: for every pixel x of a with depth z (0 = no surface:
// a point at infinity, rotation only), flow = proj_b(unproj_a(x, z)) - x. H*W*2 (u, v) interleaved.
// Points behind camera b get NaN.
std::vector<float> ground_truth_flow(const std::vector<float>& depth_a, const Camera& a, const Camera& b);

// Bilinear backward warp: out(x) = img(x + flow(x)) (edge-clamped), channels interleaved.
std::vector<float> warp_by_flow(const std::vector<float>& img, uint32_t width, uint32_t height, uint32_t channels,
                                const std::vector<float>& flow);

// PSNR (dB) of two linear images as 8-bit sRGB PNGs hold them (metrics/srgb_metrics.h).
double psnr_srgb(const std::vector<float>& a, const std::vector<float>& b);
// PSNR and SSIM of two linear H*W*3 interleaved images as 8-bit sRGB PNGs hold them.
metrics::Scores scores_srgb(const std::vector<float>& a, const std::vector<float>& b, uint32_t width, uint32_t height);

struct Interval {   // passed to the interval callback
  int view, index;  // training view, interval k (frames k -> k + 1)
  double s0, s1, t0, t1;
  const Frame& a;
  const Frame& b;
  const Camera& cam_a;
  const Camera& cam_b;
  const std::vector<float>& flow;  // ground truth a -> b
  double max_motion_px;
};
using IntervalCallback = std::function<void(const Interval&)>;

struct TrainViewResult {
  std::string name;
  Camera gt_camera;        // mid-exposure pose (noise free)
  Camera recorded_camera;  // the pose written to the dataset (with pose noise)
  double t0 = 0, t1 = 0;
  std::vector<double> times;    // sub-frame times (seconds), first = t0, last = t1
  std::vector<Camera> poses;    // sub-frame cameras
  std::vector<float> blurry;    // H*W*3 linear
  Frame sharp_mid;              // sharp frame at mid-exposure (rgb + depth)
  std::vector<float> mid_flow;  // ground-truth flow of the interval starting at mid-exposure
  double mean_blur_px = 0;      // sum over intervals of the mean |flow|
  double max_step_px = 0;       // largest pixel motion between consecutive sub-frames
  double shake_scale = 0;
};

struct NovelViewResult {
  std::string name;
  Camera camera;
  Frame frame;
};

struct SimStats {
  double seconds = 0;
  size_t events = 0;
  size_t subframes = 0;
  double mean_blur_px = 0, max_step_px = 0;
  // Mean over training views vs the mid-exposure frame, on 8-bit sRGB images.
  double psnr_blurry = 0, psnr_edi = 0, ssim_blurry = 0, ssim_edi = 0;
};

struct SimResult {
  SimParams params;
  std::string scene_source;
  std::vector<TrainViewResult> train;
  std::vector<NovelViewResult> novel;
  EventStream events;
  double near = 0, far = 0;
  SimStats stats;
};

class Simulator {
 public:
  Simulator(gpu::Context& ctx, const Scene& scene, const SimParams& params);

  MeshRenderer& renderer() { return renderer_; }

  // Camera of training view v at exposure fraction s for a given shake scale.
  Camera shake_pose(int v, double s, double scale) const;
  // Shake scale giving the target mean blur for view v (from the mid-exposure depth).
  double calibrate_shake(int v, const Frame& mid) const;
  // Planned sub-frame fractions (0 .. 1, including 0.5).
  std::vector<double> plan_subframes(int v, const Frame& mid, double scale) const;

  // Simulates training view v (events appended to `ev`, which must be fresh for this view).
  TrainViewResult simulate_view(int v, events::EventSimulator& ev, const IntervalCallback& cb = {});
  // Everything: training views, events, novel views, EDI check, statistics.
  SimResult run(const IntervalCallback& cb = {}, bool verbose = false);

 private:
  gpu::Context& ctx_;
  SimParams p_;
  MeshRenderer renderer_;
  std::vector<Camera> train_, novel_;
  std::vector<std::array<double, 54>> shake_terms_;  // per view: 6 DoF x 3 terms x (amplitude, frequency, phase)
  std::vector<std::array<double, 12>> jerk_terms_;   // per view: 6 DoF x (velocity change, time); "jerk" only
  double target_dist_ = 1;
};

}  // namespace evflow::sim
