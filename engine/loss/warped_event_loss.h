// The warped-event loss L_ev^w (paper Eq. 6-7; docs/losses.md). For each interval i of an
// exposure's 2N+1 virtual frames, j = i + 1:
//
//   M_i = the interval's events moved to t_j along its flow (threshold-weighted, signed,
//         bilinear votes: events/warped_events.h), fixed by the data and the flow;
//   P_i = -(grad L_j . d_i),  L_j = log(eps + luminance of frame j), d_i the interval's
//         displacement (pixels), grad by central differences: the brightness change that moving
//         frame j's edges by d_i makes, at the edges' positions at t_j;
//   l_i = || M_i / ||M_i|| - P_i / ||P_i|| ||^2 (norms floored as the event loss's),
//   L   = (1 / 2N) sum_i l_i,
//
// over interior pixels. The paper warps the gradient of frame i to t_j; EvFlow renders frame j
// itself, so it takes that frame's gradient: the image the warp approximates, without a
// resampling. Gradients reach frame j's render (and through it the splats, poses and knots),
// never the flow.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "loss/event_pooling.h"
#include "loss/loss_term.h"

namespace evflow {

struct WarpedEventOptions {
  float eps = 1e-3f;             // L = log(eps + Y), the event model's eps
  float norm_floor_rms = 1e-3f;  // per-pixel RMS below which a norm is floored
  uint32_t pool = 1;             // side of the pooling cells (loss/event_pooling.h)
};

class WarpedEventLoss : public ExposureLossTerm {
 public:
  // planes[v]: training view v's intervals one after another, each M, dx, dy (H * W floats
  // each); every view has the same number of intervals.
  WarpedEventLoss(gpu::Context& ctx, uint32_t width, uint32_t height, const std::vector<std::vector<float>>& planes,
                  float weight, WarpedEventOptions options = {});
  using ExposureLossTerm::record;
  void record(gpu::Commands& cmd, const ExposureFrames& frames, float weight) override;
  uint32_t intervals() const { return intervals_; }
  const WarpedEventOptions& options() const { return options_; }
  // Replaces view v's planes (the same size; its flow changed: flow=model).
  void set_view_planes(uint32_t view, const std::vector<float>& planes);
  // What the loss compares for interval i of view v, given frame j = i + 1 (planar linear RGB):
  // the measured warped events M and the predicted change P, H * W each (0 off the interior).
  // Runs the forward kernel alone and waits; no value or gradient is touched.
  std::pair<std::vector<float>, std::vector<float>> compared(gpu::Commands& cmd, uint32_t view, uint32_t interval,
                                                             const gpu::Buffer& frame);

 private:
  void check(const ExposureFrames& f) const;
  void check_view(uint32_t view) const;
  // Records interval i's forward kernel (M, P into scratch_, workgroup sums into partials_).
  void record_forward(gpu::Commands& cmd, uint32_t view, uint32_t interval, const gpu::Buffer& frame, float weight);

  uint32_t width_, height_, intervals_ = 0;
  WarpedEventOptions options_;
  uint32_t cell_groups_ = 0;  // workgroups of the forward pass: one invocation per pooling cell
  std::vector<gpu::Buffer> planes_;
  gpu::Buffer scratch_, partials_, sums_;
};

}  // namespace evflow
