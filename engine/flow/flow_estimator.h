// Optical flow from events by contrast maximisation (Gallego et al. 2018; Shiba et al. 2022), on
// the GPU (shaders/flow/, docs/flow.md). For one exposure and the intervals [t_j, t_{j+1}] of its
// virtual frames: the flows u_j (pixels over interval j) under which the exposure's events, each
// warped from its time t_k to a reference time t_r along the piecewise-constant flow
//
//   x' = x_k + sum_j lever_j(t_k, t_r) u_j(x_k),  lever_j = the signed part of [t_k, t_r] in
//        interval j, in interval lengths (within one interval: x_k + (t_r - t_k) u_j(x_k)),
//
// stack into the sharpest images of warped events (IWE). The references are the exposure's
// start, middle and end (weights 1/4, 1/2, 1/4); each IWE is blurred (Gaussian, kFlowBlurSigma) and
// scored by its summed squared gradient G, normalised by its value with zero flow (Shiba's
// normalised gradient magnitude: collapsing the events into a few pixels at one reference spreads
// them at the others, so it does not pay):
//
//   loss(u) = - sum_r w_r G_r(u) / G_r(0) + tv_weight * sum_j TV(u_j)
//             + temporal_weight * mean_j,nodes |u_{j+1} - u_j|^2.
//
// Coarse to fine in space, then in time: one flow for the whole exposure (every u_j the same), a
// node grid (flow/flow_grid.h) refined 1 -> 2x2 -> ... tiles while the IWEs go from coarse images
// (large motions of fine textures have many local optima at full resolution) to the sensor's;
// then neighbouring intervals tied in ever smaller groups, and each interval's own flow from there.
// Every stage is Adam on the analytic gradients the shaders compute.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "flow/flow_grid.h"
#include "flow/pixel_events.h"
#include "gpu/buffer.h"
#include "gpu/commands.h"

namespace evflow::flow {

struct FlowOptions {
  std::vector<uint32_t> tiles = {1, 2, 4, 8};            // the pyramid of the exposure's flow
  std::vector<uint32_t> image_scale = {4, 2, 1, 1};      // each level's IWE is this much coarser
  std::vector<uint32_t> event_stride = {8, 4, 4, 4};     // each level uses every stride-th event
  std::vector<uint32_t> iterations = {12, 8, 5, 4};      // its Adam steps per level
  std::vector<uint32_t> time_groups = {2, 3, 6};         // then neighbouring intervals tied in groups
  std::vector<uint32_t> time_iterations = {10, 10, 10};  // Adam steps per grouping
  uint32_t interval_iterations = 16;                     // then the intervals' own flows
  uint32_t interval_event_stride = 4;                    // from every stride-th event
  double lr = 0.1;                // Adam step (pixels per interval) at the first level, decaying to a tenth
  double lr_level = 0.6;          // each finer level's step, relative to the one before
  double lr_intervals = 1e-3;     // the groupings' and the intervals' own flows' step, as a fraction
                                  // of the sensor's diagonal (0.43 px at 346x260)
  double tv_weight = 0.01;        // weight of each grid's total variation
  double temporal_weight = 0.01;  // weight of the mean squared change of the flow between intervals
  void validate() const;          // throws std::invalid_argument naming the bad setting
};

struct IntervalFlow {
  FlowGrid grid;
  uint32_t events = 0;  // events inside the interval
};

struct ExposureFlow {
  uint32_t width = 0, height = 0;
  std::vector<double> frame_u;  // the 2N+1 frame times, normalised to the exposure
  std::vector<IntervalFlow> intervals;
  double contrast = 1;  // sum_r w_r G_r(u) / G_r(0): 1 with zero flow, larger when sharper
};

// The GPU's answer: G per reference and, when asked, the gradient of sum_r scale[r] G_r with
// respect to each interval's nodes.
struct ContrastEval {
  std::vector<double> g;                       // 3
  std::vector<std::vector<double>> node_grad;  // per interval, nodes * 2
};

class FlowEstimator {
 public:
  FlowEstimator(gpu::Context& ctx, FlowOptions options = {});

  // Uploads one exposure's events; evaluate() and iwe() use them.
  void set_events(const PixelEvents& events);
  // Scores one grid per interval between consecutive `frame_u` (same tile count) on the events.
  // The IWEs are `image_scale` times coarser than the sensor; every `stride`-th event (by index in
  // the pixel-by-pixel order) takes part.
  ContrastEval evaluate(const std::vector<double>& frame_u, const std::vector<FlowGrid>& grids,
                        const std::vector<float>& scale, bool gradient, uint32_t image_scale = 1, uint32_t stride = 1);
  // The IWE (H * W, events per pixel, unblurred) at reference r of the last evaluate (at image
  // scale 1).
  std::vector<float> iwe(uint32_t r) const;

  // The flow of every interval between consecutive `frame_u` (normalised times, increasing, in
  // [0, 1], at most 17) of the exposure whose events are given.
  ExposureFlow estimate(const PixelEvents& events, const std::vector<double>& frame_u);

  const FlowOptions& options() const { return options_; }
  // GPU time per stage summed over every evaluate so far (ms, in recording order), and their count.
  const std::vector<std::pair<std::string, double>>& stage_ms() const { return stage_ms_; }
  uint64_t evaluations() const { return evaluations_; }

 private:
  void record_contrast(gpu::Commands& cmd, uint32_t intervals, uint32_t tiles, uint32_t image_scale, uint32_t stride,
                       bool gradient);
  // The per-reference scales -w_r / G_r(0) at this level.
  std::vector<float> normalisation(const std::vector<double>& frame_u, uint32_t tiles, uint32_t image_scale,
                                   uint32_t stride);
  void optimise_level(const std::vector<double>& frame_u, std::vector<FlowGrid>& grids, const std::vector<float>& scale,
                      uint32_t iterations, double lr, uint32_t groups, uint32_t image_scale, uint32_t stride);

  gpu::Context& ctx_;
  FlowOptions options_;
  uint32_t width_ = 0, height_ = 0;
  uint64_t last_image_pixels_ = 0;
  std::vector<std::pair<std::string, double>> stage_ms_;
  uint64_t evaluations_ = 0;
  uint32_t busy_pixels_ = 0, events_ = 0;
  uint32_t grad_field_zeroed_ = 0;  // intervals of grad_field_ cleared for the current events (0: none)
  gpu::Buffer pixel_first_, pixel_order_, event_time_, event_slot_, intervals_, nodes_, iwe_, blur_tmp_, blurred_,
      adjoint_, scale_, partials_, quads_, positions_, grad_field_, tile_grad_;
};

// The weight of reference r (start, middle, end) in the loss.
double flow_ref_weight(uint32_t r);

}  // namespace evflow::flow
