#include "train/image_model.h"

#include <stdexcept>
#include <string>

#include "train/train_layout.h"

namespace evflow {

ImageModel::ImageModel(gpu::Context& ctx, uint32_t frames, uint32_t width, uint32_t height, LossSpace space,
                       uint32_t upsample)
    : ctx_(ctx),
      frames_(frames),
      width_(width),
      height_(height),
      upsample_(upsample),
      values_(size_t(width) * height * 3),
      space_(space),
      identity_(frames == 1 && space == LossSpace::Srgb),
      v_prediction_(ctx, size_t(width) * height * 12, "v_prediction") {
  if (frames == 0) throw std::invalid_argument("image model: no frames");
  if (upsample == 0 || (upsample > 1 && frames < 2))
    throw std::invalid_argument("image model: upsampling needs M >= 1 and, for M > 1, at least 2 frames");
  if (identity_) return;
  for (uint32_t i = 0; i < frames; ++i) {
    linear_.emplace_back(ctx, values_ * 4, "linear_frame");
    v_render_.emplace_back(ctx, values_ * 4, "v_render");
    if (upsample > 1) v_share_.emplace_back(ctx, values_ * 4, "v_frame_share");
  }
  if (frames > 1) mean_ = gpu::Buffer(ctx, values_ * 4, "blur_mean_image");
  if (space == LossSpace::Srgb) {
    encoded_ = gpu::Buffer(ctx, values_ * 4, "prediction_srgb");
    v_mean_ = gpu::Buffer(ctx, values_ * 4, "v_mean");
  }
}

namespace {

// The workgroups for kernels that take n floats four to an invocation, group_size invocations a group.
gpu::Groups quad_groups(const gpu::Commands& cmd, uint64_t n, uint32_t group_size) {
  return cmd.linear_groups(gpu::Commands::div_up(gpu::Commands::div_up(n, 4), group_size));
}

}  // namespace

void record_accumulate(gpu::Commands& cmd, uint64_t n, float scale, bool add, const gpu::Buffer& x,
                       const gpu::Buffer& y) {
  shaderio::AccumulatePC pc{uint32_t(n), scale, add ? 1u : 0u, 0};
  cmd.dispatch("train/accumulate", {{shaderio::kTrainAccumulateBindX, x}, {shaderio::kTrainAccumulateBindY, y}}, pc,
               quad_groups(cmd, n, shaderio::kAccumulateGroupSize));
}

void record_colour(gpu::Commands& cmd, uint32_t op, uint64_t n, const gpu::Buffer& x, const gpu::Buffer& g,
                   const gpu::Buffer& y) {
  static const char* const kNames[] = {"train/colour_decode", "train/colour_encode", "train/colour_decode_bwd",
                                       "train/colour_encode_bwd"};
  static_assert(shaderio::kColourDecode == 0 && shaderio::kColourEncode == 1 && shaderio::kColourDecodeBwd == 2 &&
                shaderio::kColourEncodeBwd == 3);
  if (op > shaderio::kColourEncodeBwd) throw std::invalid_argument("colour conversion: unknown op");
  shaderio::ColourPC pc{uint32_t(n), 0.0f, 0, 0};
  const gpu::Groups groups = quad_groups(cmd, n, shaderio::kColourGroupSize);
  if (op >= shaderio::kColourDecodeBwd)  // the forward builds have no gradient binding
    cmd.dispatch(kNames[op], {{shaderio::kColourBindX, x}, {shaderio::kColourBindG, g}, {shaderio::kColourBindY, y}},
                 pc, groups);
  else
    cmd.dispatch(kNames[op], {{shaderio::kColourBindX, x}, {shaderio::kColourBindY, y}}, pc, groups);
}

void record_decode_mean(gpu::Commands& cmd, uint64_t n, float scale, bool add, const gpu::Buffer& x,
                        const gpu::Buffer& y, const gpu::Buffer& mean) {
  shaderio::ColourPC pc{uint32_t(n), scale, add ? 1u : 0u, 0};
  cmd.dispatch("train/colour_decode_mean",
               {{shaderio::kColourBindX, x},
                {shaderio::kColourBindY, y},
                {shaderio::kColourBindMean, mean},
                {shaderio::kColourBindMeanIn, mean}},
               pc, quad_groups(cmd, n, shaderio::kColourGroupSize));
}

void ImageModel::forward(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders, const gpu::Buffer* flow) {
  if (renders.size() != frames_) throw std::invalid_argument("image model: wrong number of renders");
  if (upsample_ > 1 && !flow) throw std::invalid_argument("image model: upsampling needs the view's flow");
  renders_ = renders;
  flow_ = flow;
  if (identity_) return;
  if (decodes_at_once())
    record_decode_mean_all(cmd);
  else
    for (uint32_t i = 0; i < frames_; ++i)
      if (frames_ > 1)
        record_decode_mean(cmd, values_, 1.0f / float(mean_count()), i > 0, *renders[i], linear_[i], mean_);
      else
        colour(cmd, shaderio::kColourDecode, *renders[i], *renders[i], linear_[i]);
  if (upsample_ > 1) upsample_forward(cmd, *flow);
  const gpu::Buffer& m = frames_ > 1 ? mean_ : linear_[0];
  if (space_ == LossSpace::Srgb) colour(cmd, shaderio::kColourEncode, m, m, encoded_);
}

bool ImageModel::decodes_at_once() const {
  return frames_ >= 2 && frames_ <= shaderio::kDecodeMeanMaxFrames && ctx_.caps().fits_bindings(frames_ + 1, frames_);
}

// Every frame's decode and the mean in one pass (train/decode_mean_f<F>), the same values as a
// colour_decode_mean pass per frame.
void ImageModel::record_decode_mean_all(gpu::Commands& cmd) {
  shaderio::ColourPC pc{uint32_t(values_), 1.0f / float(mean_count()), 0, 0};
  std::vector<gpu::Bind> binds = {{shaderio::kDecodeMeanBindMean, mean_}};
  for (uint32_t k = 0; k < frames_; ++k)
    binds.insert(binds.end(),
                 {{shaderio::kDecodeMeanBindXs[k], *renders_[k]}, {shaderio::kDecodeMeanBindYs[k], linear_[k]}});
  cmd.dispatch("train/decode_mean_f" + std::to_string(frames_), binds, pc,
               quad_groups(cmd, values_, shaderio::kColourGroupSize));
}

// The sub-frames of every interval, added into the mean: each target's taps once (kept for the
// backward), then the sampling.
void ImageModel::upsample_forward(gpu::Commands& cmd, const gpu::Buffer& flow) {
  const uint64_t hw = uint64_t(width_) * height_, subframes = uint64_t(frames_ - 1) * (upsample_ - 1);
  if (flow.size() < 2 * hw * (frames_ - 1) * 4)
    throw std::invalid_argument("image model: the flow holds fewer than 2 planes per interval");
  const uint64_t tap_bytes = subframes * hw * shaderio::kUpsampleTapFloats * 4;
  ctx_.check_binding_size(tap_bytes, "upsampled blur taps");
  if (taps_.size() < tap_bytes) taps_ = gpu::Buffer(ctx_, tap_bytes, "upsample_taps");
  for (uint32_t i = 0; i + 1 < frames_; ++i) {
    shaderio::UpsamplePC pc{width_, height_, i, upsample_, 1.0f / float(mean_count()), 0, 0, 0};
    cmd.dispatch("train/upsample_taps",
                 {{shaderio::kUpsampleTapsBindFlow, flow}, {shaderio::kUpsampleTapsBindTaps, taps_}}, pc,
                 cmd.linear_groups(gpu::Commands::div_up(hw * (upsample_ - 1), shaderio::kUpsampleGroupSize)));
    cmd.dispatch("train/upsample",
                 {{shaderio::kUpsampleBindTaps, taps_},
                  {shaderio::kUpsampleBindFrame, linear_[i]},
                  {shaderio::kUpsampleBindMean, mean_}},
                 pc, cmd.linear_groups(gpu::Commands::div_up(hw, shaderio::kUpsampleGroupSize)));
  }
}

void ImageModel::frame_share(gpu::Commands& cmd, uint32_t i, const gpu::Buffer& out) {
  const gpu::Buffer& g = (identity_ || space_ == LossSpace::Linear) ? v_prediction_ : v_mean_;
  if (upsample_ == 1 || i + 1 == frames_) {
    cmd.copy(g, out, values_ * 4);
    return;
  }
  const uint64_t hw = uint64_t(width_) * height_;
  shaderio::UpsamplePC pc{width_, height_, i, upsample_, 1.0f, 0, 0, 0};
  cmd.dispatch("train/upsample_bwd",
               {{shaderio::kUpsampleBwdBindFlow, *flow_},
                {shaderio::kUpsampleBwdBindTaps, taps_},
                {shaderio::kUpsampleBwdBindGrad, g},
                {shaderio::kUpsampleBwdBindShare, out}},
               pc, cmd.linear_groups(gpu::Commands::div_up(hw, shaderio::kUpsampleGroupSize)));
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
  for (uint32_t i = 0; i < frames_; ++i) {
    const gpu::Buffer* g = shared ? shared : frame_grads[i];
    if (shared && upsample_ > 1) {  // each frame's own share
      frame_share(cmd, i, v_share_[i]);
      g = &v_share_[i];
    }
    colour(cmd, shaderio::kColourDecodeBwd, *renders_[i], *g, v_render_[i]);
  }
}

}  // namespace evflow
