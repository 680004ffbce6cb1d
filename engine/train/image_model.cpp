#include "train/image_model.h"

#include <stdexcept>

#include "train/train_layout.h"

namespace evflow {

ImageModel::ImageModel(gpu::Context& ctx, uint32_t frames, size_t values, LossSpace space)
    : ctx_(ctx),
      frames_(frames),
      values_(values),
      space_(space),
      identity_(frames == 1 && space == LossSpace::Srgb),
      v_prediction_(ctx, values * 4, "v_prediction") {
  if (frames == 0) throw std::invalid_argument("image model: no frames");
  if (identity_) return;
  for (uint32_t i = 0; i < frames; ++i) {
    linear_.emplace_back(ctx, values * 4, "linear_frame");
    v_render_.emplace_back(ctx, values * 4, "v_render");
  }
  if (frames > 1) mean_ = gpu::Buffer(ctx, values * 4, "blur_mean_image");
  if (space == LossSpace::Srgb) {
    encoded_ = gpu::Buffer(ctx, values * 4, "prediction_srgb");
    v_mean_ = gpu::Buffer(ctx, values * 4, "v_mean");
  }
}

void ImageModel::colour(gpu::Commands& cmd, uint32_t op, const gpu::Buffer& x, const gpu::Buffer& g,
                        const gpu::Buffer& y) {
  shaderio::ColourPC pc{uint32_t(values_), op, 0, 0};
  cmd.dispatch("train/colour", {{shaderio::kColourBindX, x}, {shaderio::kColourBindG, g}, {shaderio::kColourBindY, y}},
               pc, cmd.linear_groups(gpu::Commands::div_up(values_, shaderio::kColourGroupSize)));
}

void ImageModel::forward(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders) {
  if (renders.size() != frames_) throw std::invalid_argument("image model: wrong number of renders");
  renders_ = renders;
  if (identity_) return;
  for (uint32_t i = 0; i < frames_; ++i) colour(cmd, shaderio::kColourDecode, *renders[i], *renders[i], linear_[i]);
  if (frames_ > 1)
    for (uint32_t i = 0; i < frames_; ++i) {
      shaderio::AccumulatePC pc{uint32_t(values_), 1.0f / float(frames_), i > 0 ? 1u : 0u, 0};
      cmd.dispatch("train/accumulate",
                   {{shaderio::kTrainAccumulateBindX, linear_[i]}, {shaderio::kTrainAccumulateBindY, mean_}}, pc,
                   cmd.linear_groups(gpu::Commands::div_up(values_, shaderio::kAccumulateGroupSize)));
    }
  const gpu::Buffer& m = frames_ > 1 ? mean_ : linear_[0];
  if (space_ == LossSpace::Srgb) colour(cmd, shaderio::kColourEncode, m, m, encoded_);
}

const gpu::Buffer& ImageModel::prediction() const {
  if (identity_) return *renders_.at(0);
  if (space_ == LossSpace::Srgb) return encoded_;
  return frames_ > 1 ? mean_ : linear_[0];
}

const gpu::Buffer& ImageModel::mean_grad(gpu::Commands& cmd) {
  if (identity_ || space_ == LossSpace::Linear) return v_prediction_;
  const gpu::Buffer& m = frames_ > 1 ? mean_ : linear_[0];
  colour(cmd, shaderio::kColourEncodeBwd, m, v_prediction_, v_mean_);
  return v_mean_;
}

void ImageModel::render_grads(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads) {
  if (identity_) return;
  if (!frame_grads.empty() && frame_grads.size() != frames_)
    throw std::invalid_argument("image model: wrong number of frame gradients");
  const gpu::Buffer* shared = frame_grads.empty() ? &mean_grad(cmd) : nullptr;
  for (uint32_t i = 0; i < frames_; ++i)
    colour(cmd, shaderio::kColourDecodeBwd, *renders_[i], shared ? *shared : *frame_grads[i], v_render_[i]);
}

}  // namespace evflow
