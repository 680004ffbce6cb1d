// The differentiable tile-based splat rasterizer (docs/rasterizer.md): forward and backward as
// compute shaders. Gaussian parameters, images and gradients stay in GPU buffers.
#pragma once
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "gpu/commands.h"
#include "scan/prefix_sum.h"
#include "sort/radix_sort.h"
#include "splat/gaussians.h"

namespace evflow {

// Parameters (or their gradients) on the GPU, same layout as GaussianCloud but with the SH
// coefficients split by band (sh[l]: (2l+1) coefficients x 3 per Gaussian).
struct GaussianBuffers {
  GaussianBuffers(gpu::Context& ctx, size_t count, int sh_degree, const std::string& prefix);
  size_t count = 0;
  int sh_degree = 0;
  gpu::Buffer means, log_scales, quats, opacity_logits;
  std::array<gpu::Buffer, 4> sh;

  void upload(const GaussianCloud& cloud);
  GaussianCloud download() const;
  // Largest Gaussian count whose every buffer fits one storage binding on this device.
  static size_t max_count(const gpu::Context& ctx, int sh_degree);
};

struct RasterOutputs {
  gpu::Buffer rgb, alpha, depth;  // [3][H][W], [H][W], [H][W]
};

class Rasterizer {
 public:
  explicit Rasterizer(gpu::Context& ctx);

  // Renders; returns after the GPU finished. One scalar (the intersection count) is read back
  // between the projection and the sort to size the intersection buffers.
  void forward(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings);
  // Gradients for the last forward: v_rgb [3][H][W] and v_alpha [H][W] in GPU buffers. Writes
  // every parameter gradient into `grads`, the pose gradient (se(3), translation first) and
  // the per-Gaussian screen-space gradient norm.
  // With `accumulate`, gradients (and the screen-gradient norms) are added to what `grads`
  // holds (several renders in one step); the pose gradient is always this render's alone.
  // `grad2d_norm_into`: where the screen-gradient norms go (default: this rasterizer's own
  // buffer), so renders held by several rasterizers can add into one.
  void backward(const GaussianBuffers& params, const gpu::Buffer& v_rgb, const gpu::Buffer& v_alpha,
                GaussianBuffers& grads, bool accumulate = false, gpu::Buffer* grad2d_norm_into = nullptr);

  // Backward passes of this rasterizer use `owner`'s per-intersection gradient scratch (the
  // largest backward buffer) instead of their own: for render states kept side by side whose
  // backward passes run one after the other.
  void borrow_backward_scratch(Rasterizer& owner) { scratch_owner_ = &owner; }
  const RasterOutputs& outputs() const { return out_; }
  std::array<float, 6> pose_gradient() const;
  const gpu::Buffer& grad2d_norm() const { return grad2d_norm_; }
  gpu::Buffer& grad2d_norm() { return grad2d_norm_; }
  uint32_t num_intersections() const { return num_isects_; }
  // Stage times (ms) of the last forward and backward, in order.
  const std::vector<std::pair<std::string, double>>& stage_ms() const { return stage_ms_; }

 private:
  void set_pc(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings);
  gpu::Context& ctx_;
  gpu::Commands cmd_;
  PrefixSum scan_;
  RadixSort sort_;
  // Per Gaussian.
  gpu::Buffer proj_mean_conic_, proj_misc_, proj_color_, proj_dcolor_, tile_rect_, tiles_touched_, isect_offset_;
  // Per intersection.
  gpu::Buffer keys_, slot_from_isect_, gaussian_id_from_slot_, isect_grad_;
  const gpu::Buffer* sorted_slots_ = nullptr;
  uint64_t grad_plane_stride_ = 0;
  // Per tile / pixel.
  gpu::Buffer tile_range_, final_T_, last_isect_;
  RasterOutputs out_;
  // Backward.
  gpu::Buffer grad2d_norm_, pose_partial_, pose_;
  std::array<uint8_t, 128> project_pc_{}, raster_pc_{};
  uint32_t width_ = 0, height_ = 0, tiles_x_ = 0, tiles_y_ = 0, num_isects_ = 0, depth_bits_ = 0, sort_bits_ = 0;
  size_t count_ = 0;
  Rasterizer* scratch_owner_ = nullptr;
  std::string block_suffix_;  // "" (one pixel per invocation) or "_block" (see set_pc)
  std::vector<std::pair<std::string, double>> stage_ms_;
};

}  // namespace evflow
