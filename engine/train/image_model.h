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
//
// Flow-upsampled blur (paper Eq. 9, upsample M > 1): each interval i of the frames also gives
// M - 1 sub-frames, frame i moved along the interval's flow, S_m(L_i)(x) = L_i(x - (m/M) d_i(x))
// (bilinear; d_i: the displacement over the interval, so the sub-frame shows the scene m/M of the
// way to frame i + 1), and M is the mean of all 2NM + 1 frames. Taps are limited to those whose
// own warped position lies within kUpsampleReach of the target (shaders/train/train_layout.h), so
// that the exact adjoint is a gather: no float atomics, a fixed order.
#pragma once
#include <cstdint>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "train/train_config.h"

namespace evflow {

// Records y = op(x[, g]) over n floats, op one of the colour conversions of train_layout.h
// (kColourDecode, kColourEncode, kColourDecodeBwd, kColourEncodeBwd; g is read by the last two).
void record_colour(gpu::Commands& cmd, uint32_t op, uint64_t n, const gpu::Buffer& x, const gpu::Buffer& g,
                   const gpu::Buffer& y);

// Records y = decode(x) and mean = (add ? mean : 0) + scale * y over n floats, in one pass
// (train/colour_decode_mean).
void record_decode_mean(gpu::Commands& cmd, uint64_t n, float scale, bool add, const gpu::Buffer& x,
                        const gpu::Buffer& y, const gpu::Buffer& mean);
// Records y = (add ? y : 0) + scale * x over n floats.
void record_accumulate(gpu::Commands& cmd, uint64_t n, float scale, bool add, const gpu::Buffer& x,
                       const gpu::Buffer& y);

class ImageModel {
 public:
  // frames: renders per step (2N+1, or 1 in plain mode) of width x height; upsample: M (1: off).
  ImageModel(gpu::Context& ctx, uint32_t frames, uint32_t width, uint32_t height, LossSpace space,
             uint32_t upsample = 1);

  bool identity() const { return identity_; }
  uint32_t frames() const { return frames_; }
  // The frames the mean averages: 2NM + 1 (frames() without upsampling).
  uint32_t mean_count() const { return frames_ + (frames_ - 1) * (upsample_ - 1); }
  uint32_t upsample() const { return upsample_; }

  // Records the forward pass over the step's renders (one per frame, in frame order). flow: with
  // upsample > 1, the view's displacement planes (dx, dy per interval, H * W floats each).
  void forward(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders, const gpu::Buffer* flow = nullptr);
  // The image the image terms compare with the target.
  const gpu::Buffer& prediction() const;
  // Frame i in linear light (what exposure terms see). Not available when identity().
  const gpu::Buffer& linear_frame(uint32_t i) const { return linear_[i]; }

  // Where the image terms write d(loss)/d(prediction), already divided by mean_count() (each
  // frame's share of the mean).
  const gpu::Buffer& prediction_grad() const { return v_prediction_; }
  // Records d(loss)/d(M) / mean_count() from prediction_grad(); returns the buffer that holds it.
  const gpu::Buffer& mean_grad(gpu::Commands& cmd);
  // Records frame i's share of the mean's gradient into `out` (the mean_grad() of the step,
  // recorded before): a copy of it, plus its sub-frames' adjoint when upsampling.
  void frame_share(gpu::Commands& cmd, uint32_t i, const gpu::Buffer& out);
  // Records each render's gradient. frame_grads: per frame d(loss)/d(L_i) with the mean's share
  // already in it (exposure terms on), or empty (then every frame takes the mean's share). Not
  // needed when the exposure terms wrote render_grad() themselves (LossTerms::record_exposure_terms).
  void render_grads(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads);
  const gpu::Buffer& render_grad(uint32_t i) const { return identity_ ? v_prediction_ : v_render_[i]; }

 private:
  void colour(gpu::Commands& cmd, uint32_t op, const gpu::Buffer& x, const gpu::Buffer& g, const gpu::Buffer& y) {
    record_colour(cmd, op, values_, x, g, y);
  }
  void upsample_forward(gpu::Commands& cmd, const gpu::Buffer& flow);
  // Whether one pass decodes every frame and makes their mean (2..kDecodeMeanMaxFrames frames, and
  // the device binds them all), else a pass per frame.
  bool decodes_at_once() const;
  void record_decode_mean_all(gpu::Commands& cmd);
  gpu::Context& ctx_;
  uint32_t frames_, width_, height_, upsample_;
  size_t values_;
  const gpu::Buffer* flow_ = nullptr;
  std::vector<gpu::Buffer> v_share_;  // per frame, when upsampling without exposure terms
  gpu::Buffer taps_;                  // the sub-frames' taps of the last forward
  LossSpace space_;
  bool identity_;
  std::vector<const gpu::Buffer*> renders_;
  std::vector<gpu::Buffer> linear_, v_render_;
  gpu::Buffer mean_, encoded_, v_prediction_, v_mean_;
};

}  // namespace evflow
