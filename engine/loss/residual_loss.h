// The event-residual loss L_res (the paper's Eq. 9) over one exposure's 2N+1 virtual frames F_i
// (linear RGB, planar):
//   L = 1/(2N+1) * sum_i mean over the C*H*W values of ((F_i - F_N) - R_i)^2,
// R_i the residual prior's I(t_i) - I(t_N) for the view (prior/residual_prior.h), set once per
// view; R_N = 0, so the middle frame's own term is zero. Values: [L].
#pragma once
#include <cstdint>
#include <vector>

#include "loss/loss_term.h"

namespace evflow {

class ResidualLoss : public ExposureLossTerm {
 public:
  // views: training views; frames: 2N+1 (odd, >= 3).
  ResidualLoss(gpu::Context& ctx, uint32_t width, uint32_t height, uint32_t frames, uint32_t views, float weight);

  uint32_t frames() const { return frames_; }
  // View v's residuals: (frames - 1) planar RGB images, the non-middle frames in order.
  void set_view_residuals(uint32_t view, const std::vector<float>& residuals);
  // What set_view_residuals() stored for view `view` (read back from the device).
  std::vector<float> view_residuals(uint32_t view) const;

  void record(gpu::Commands& cmd, const ExposureFrames& frames, float weight) override;
  using ExposureLossTerm::record;

 private:
  uint32_t width_, height_, frames_;
  std::vector<std::vector<gpu::Buffer>> residuals_;  // [view][non-middle frame]
  std::vector<bool> set_;
  gpu::Buffer partials_;
};

}  // namespace evflow
