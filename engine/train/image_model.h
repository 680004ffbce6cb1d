// The image model of a training step: from the step's renders (display-referred sRGB, as splat
// colours are) to the image the image terms compare with the target, and back.
//
//   render C_i (sRGB) --decode--> linear frame L_i --mean over the 2N+1 frames--> M (linear light)
//   prediction P = M             (loss_space = linear; target decoded to linear)
//   prediction P = encode(M)     (loss_space = srgb;   target as stored, sRGB)
//
// The blur is physical: the frames are averaged in linear light. Exposure terms (the event loss)
// see the linear frames, since events respond to linear log intensity. Plain mode with
// loss_space = srgb is the identity (P = C_0): nothing is converted, as in 3DGS.
#pragma once
#include <cstdint>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "train/train_config.h"

namespace evflow {

class ImageModel {
 public:
  // frames: renders per step (2N+1, or 1 in plain mode); values: floats per image (3 H W).
  ImageModel(gpu::Context& ctx, uint32_t frames, size_t values, LossSpace space);

  bool identity() const { return identity_; }
  uint32_t frames() const { return frames_; }

  // Records the forward pass over the step's renders (one per frame, in frame order).
  void forward(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders);
  // The image the image terms compare with the target.
  const gpu::Buffer& prediction() const;
  // Frame i in linear light (what exposure terms see). Not available when identity().
  const gpu::Buffer& linear_frame(uint32_t i) const { return linear_[i]; }

  // Where the image terms write d(loss)/d(prediction), already divided by frames() (each
  // frame's share of the mean).
  const gpu::Buffer& prediction_grad() const { return v_prediction_; }
  // Records d(loss)/d(M) / frames() from prediction_grad(); returns the buffer that holds it.
  const gpu::Buffer& mean_grad(gpu::Commands& cmd);
  // Records each render's gradient. frame_grads: per frame d(loss)/d(L_i) with the mean's share
  // already in it (exposure terms on), or empty (then every frame takes the mean's share).
  void render_grads(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads);
  const gpu::Buffer& render_grad(uint32_t i) const { return identity_ ? v_prediction_ : v_render_[i]; }

 private:
  void colour(gpu::Commands& cmd, uint32_t op, const gpu::Buffer& x, const gpu::Buffer& g, const gpu::Buffer& y);
  gpu::Context& ctx_;
  uint32_t frames_;
  size_t values_;
  LossSpace space_;
  bool identity_;
  std::vector<const gpu::Buffer*> renders_;
  std::vector<gpu::Buffer> linear_, v_render_;
  gpu::Buffer mean_, encoded_, v_prediction_, v_mean_;
};

}  // namespace evflow
