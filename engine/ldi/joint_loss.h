// The joint loss L_joint (paper Eq. 10): for two sequences of F images of one shape (the LDI's
// frames and the splats' renders over the same crop, in the trainer's loss space),
//
//   L = (1 / F) sum_i L_img(A_i, B_i),   L_img = (1 - lambda) L1 + lambda (1 - SSIM)
//
// (BlendLoss, the trainer's image loss), with gradients into both sequences. L_img is symmetric
// in its two images (|a - b| and SSIM's formula are), so the gradient of B_i is the blend loss's
// gradient with the two images exchanged. Values: [L].
#pragma once
#include <cstdint>
#include <vector>

#include "loss/image_losses.h"
#include "loss/loss_term.h"

namespace evflow::ldi {

class JointLoss : public LossTerm {
 public:
  JointLoss(gpu::Context& ctx, ImageShape shape, float ssim_lambda, float weight);
  const ImageShape& shape() const { return blend_.shape(); }
  // grad_a[i] (+)= weight / F * dL_img(A_i, B_i)/dA_i, likewise grad_b (added into with
  // `accumulate`, else written); the value into the value slot.
  void record(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& a, const std::vector<const gpu::Buffer*>& b,
              const std::vector<const gpu::Buffer*>& grad_a, const std::vector<const gpu::Buffer*>& grad_b,
              float weight, bool accumulate);

 private:
  BlendLoss blend_;
  gpu::Buffer frame_values_;  // 3 floats per frame and a spare for the exchanged records
};

}  // namespace evflow::ldi
