// Image losses and metrics on the GPU, for planar float images img[c*H*W + y*W + x]
// (the renderer's layout): pred = A, target = B, both C x H x W.
//
//   L1Loss     L = mean |A - B|                                 values: [L]
//   SsimLoss   L = 1 - SSIM,  SSIM = mean over C*H*W of the map  values: [L, SSIM]
//   BlendLoss  L = (1 - lambda) L1 + lambda (1 - SSIM)           values: [L, L1, SSIM]
//   ImageMetrics (no gradient)                                   values: [PSNR, SSIM, MSE]
//
// SSIM: 11 x 11 Gaussian window (sigma 1.5), C1 = 0.01^2, C2 = 0.03^2, per channel, zero-padded
// "same" convolution (taps outside the image dropped, weights not renormalised): see
// shaders/loss/ssim_math.glsl for the exact definition and the backward. PSNR = -10 log10(MSE)
// for images in [0, 1].
#pragma once
#include <cstdint>

#include "gpu/commands.h"
#include "loss/loss_term.h"

namespace evflow {

struct ImageShape {
  uint32_t channels = 3, height = 0, width = 0;
  uint64_t count() const { return uint64_t(channels) * height * width; }
};

inline constexpr float kSsimC1 = 0.01f * 0.01f;
inline constexpr float kSsimC2 = 0.03f * 0.03f;
inline constexpr float kDefaultSsimLambda = 0.2f;

// Scratch and passes shared by the SSIM-based terms (two forward passes, two backward passes and
// one reduction). Not a LossTerm itself.
class SsimPipeline {
 public:
  explicit SsimPipeline(gpu::Context& ctx);
  struct Outputs {
    const gpu::Buffer* values = nullptr;  // where the reduction writes
    uint32_t first = 0;
    // Affine outputs of s = (sum of pixel terms, sum of SSIM): out[j] = dot(coeff[j], s) + offset[j].
    uint32_t count = 0;
    float coeff[4][2] = {};
    float offset[4] = {};
    uint32_t log_mask = 0;  // -10 log10 on these outputs
  };
  // pixel_l2: the per-pixel term is (A-B)^2 instead of |A-B|. When grad is given:
  //   grad (+)= ssim_grad_scale * d(sum SSIM)/dA + pixel_grad_scale * d(sum e)/dA.
  void record(gpu::Commands& cmd, const ImageShape& shape, const gpu::Buffer& a, const gpu::Buffer& b,
              const gpu::Buffer* grad, float ssim_grad_scale, float pixel_grad_scale, bool accumulate, bool pixel_l2,
              const Outputs& out, bool write_map = false);
  // The per-pixel SSIM map of the last record with write_map (the plane after the D scratch's
  // count vec4s).
  const gpu::Buffer& map_buffer() const { return d_; }
  uint64_t map_offset_bytes(const ImageShape& shape) const { return 4 * shape.count() * 4; }

 private:
  gpu::Context& ctx_;
  gpu::Buffer h_, d_, partials_;
};

class L1Loss : public ImageLossTerm {
 public:
  L1Loss(gpu::Context& ctx, ImageShape shape, float weight = 1.0f);
  void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, const gpu::Buffer& grad_out,
              float weight, bool accumulate) override;
  using ImageLossTerm::record;
  void set_shape(const ImageShape& s) { shape_ = s; }
  const ImageShape& shape() const { return shape_; }

 private:
  ImageShape shape_;
  gpu::Buffer partials_;
};

class SsimLoss : public ImageLossTerm {
 public:
  SsimLoss(gpu::Context& ctx, ImageShape shape, float weight = 1.0f);
  void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, const gpu::Buffer& grad_out,
              float weight, bool accumulate) override;
  using ImageLossTerm::record;
  void set_shape(const ImageShape& s) { shape_ = s; }
  const ImageShape& shape() const { return shape_; }
  double ssim() const { return values()[1]; }

 private:
  ImageShape shape_;
  SsimPipeline pipe_;
};

class BlendLoss : public ImageLossTerm {
 public:
  BlendLoss(gpu::Context& ctx, ImageShape shape, float lambda = kDefaultSsimLambda, float weight = 1.0f);
  void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, const gpu::Buffer& grad_out,
              float weight, bool accumulate) override;
  using ImageLossTerm::record;
  void set_shape(const ImageShape& s) { shape_ = s; }
  const ImageShape& shape() const { return shape_; }
  float lambda() const { return lambda_; }
  void set_lambda(float l) { lambda_ = l; }

 private:
  ImageShape shape_;
  float lambda_;
  SsimPipeline pipe_;
};

// Evaluation metrics (forward only): PSNR from the MSE, and mean SSIM, in one pass set.
class ImageMetrics {
 public:
  explicit ImageMetrics(gpu::Context& ctx, ImageShape shape);
  void set_shape(const ImageShape& s) { shape_ = s; }
  // write_map: keep the per-pixel SSIM map (ssim_map_buffer(), N = C*H*W floats from
  // ssim_map_offset_bytes()).
  void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, bool write_map = false);
  struct Values {
    double psnr = 0, ssim = 0, mse = 0;
  };
  Values read() const;  // one download of three floats, after the submit
  const gpu::Buffer& ssim_map_buffer() const { return pipe_.map_buffer(); }
  uint64_t ssim_map_offset_bytes() const { return pipe_.map_offset_bytes(shape_); }

 private:
  ImageShape shape_;
  SsimPipeline pipe_;
  gpu::Buffer values_;
};

}  // namespace evflow
