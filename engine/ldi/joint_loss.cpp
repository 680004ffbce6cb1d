#include "ldi/joint_loss.h"

#include <stdexcept>
#include <string>

#include "ldi/ldi_layout.h"

namespace evflow::ldi {

JointLoss::JointLoss(gpu::Context& ctx, ImageShape shape, float ssim_lambda, float weight)
    : LossTerm(ctx, "joint", weight, 1),
      blend_(ctx, shape, ssim_lambda, 1.0f),
      frame_values_(ctx, 16, "joint_values") {}

void JointLoss::record(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& a,
                       const std::vector<const gpu::Buffer*>& b, const std::vector<const gpu::Buffer*>& grad_a,
                       const std::vector<const gpu::Buffer*>& grad_b, float weight, bool accumulate) {
  const size_t F = a.size();
  if (F == 0 || b.size() != F || grad_a.size() != F || grad_b.size() != F)
    throw std::invalid_argument("joint loss: " + std::to_string(F) + " images against " + std::to_string(b.size()) +
                                ", with " + std::to_string(grad_a.size()) + " and " + std::to_string(grad_b.size()) +
                                " gradients");
  frame_values_.ensure((F + 1) * 3 * 4);
  const float w = weight / float(F);
  for (size_t i = 0; i < F; ++i) {
    blend_.set_value_slot(frame_values_, uint32_t(3 * i));
    blend_.record(cmd, *a[i], *b[i], *grad_a[i], w, accumulate);
    blend_.set_value_slot(frame_values_, uint32_t(3 * F));
    blend_.record(cmd, *b[i], *a[i], *grad_b[i], w, accumulate);
  }
  shaderio::LdiMeanPC pc{uint32_t(F), 3, 0, value_offset(), 1.0f / float(F), 0, 0, 0};
  cmd.dispatch("ldi/mean_values",
               {{shaderio::kLdiMeanBindSrc, frame_values_}, {shaderio::kLdiMeanBindValues, value_buffer()}}, pc,
               gpu::Groups{1, 1, 1});
}

}  // namespace evflow::ldi
