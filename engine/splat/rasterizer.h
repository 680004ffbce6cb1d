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
#include "splat/splat_layout.h"

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
  gpu::Buffer rgb, alpha, depth;  // [3][H][W], [H][W], [H][W] (depth: see RenderSettings::depth)
};

// What one render leaves for its backward pass: the projected Gaussians, the sorted tile
// intersections, each pixel's compositing state, the images and the push constants. The caller
// owns it: renders kept side by side (the virtual frames of an exposure) each keep a state,
// and any of them can go back through one Rasterizer in any order. A state is reused across
// renders (its buffers only grow).
class RenderState {
 public:
  explicit RenderState(gpu::Context& ctx);
  const RasterOutputs& outputs() const { return out_; }
  uint32_t num_intersections() const { return num_isects_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }

 private:
  friend class Rasterizer;
  const gpu::Buffer& sorted_slots() const { return sorted_in_alt_ ? slots_alt_ : slot_from_isect_; }
  // Per Gaussian.
  gpu::Buffer proj_mean_conic_, proj_misc_, proj_color_, proj_dcolor_, tile_rect_, tiles_touched_, isect_offset_;
  // Per intersection (the sort ping-pongs between the two key/slot pairs).
  gpu::Buffer keys_, slot_from_isect_, keys_alt_, slots_alt_, gaussian_id_from_slot_;
  gpu::Buffer block_words_;  // block kernels: each loaded word's bit sets per block (splat_layout.h)
  bool sorted_in_alt_ = false;
  // Per tile / pixel.
  gpu::Buffer tile_range_, final_T_, last_isect_;
  RasterOutputs out_;
  shaderio::ProjectPC project_pc_{};
  shaderio::RasterPC raster_pc_{};
  uint32_t width_ = 0, height_ = 0, num_isects_ = 0, sort_bits_ = 0;
  size_t count_ = 0;
  bool depth_ = true;  // RenderSettings::depth of the last render
};

// The compositing kernels a Rasterizer runs.
struct RasterKernels {
  bool block = false;           // a block of pixels per invocation (CPU drivers), else one pixel
  bool subgroup_reduce = true;  // backward: subgroupAdd before the shared add (GPUs), else per-lane adds
  // The device's choice, with the overrides of the context's options (raster_kernel, subgroup_reduce).
  static RasterKernels for_context(const gpu::Context& ctx);
};

// The kernels and what renders share: the sort's and the backward pass's scratch, the
// screen-space gradient norms and the pose gradient of the last backward.
class Rasterizer {
 public:
  explicit Rasterizer(gpu::Context& ctx);
  Rasterizer(gpu::Context& ctx, const RasterKernels& kernels);

  // Renders into `state`; returns after the GPU finished. One scalar (the intersection count)
  // is read back between the projection and the sort to size the intersection buffers.
  void forward(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings, RenderState& state);
  // The same into a new state.
  RenderState forward(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings);
  // Several renders of the same Gaussians (an exposure's virtual frames), one state per camera:
  // what forward() does for each, in two submits and one wait for all the counts.
  void forward(const GaussianBuffers& params, const std::vector<Camera>& cams, const RenderSettings& settings,
               const std::vector<RenderState*>& states);
  // Gradients for the render in `state`: v_rgb [3][H][W] and v_alpha [H][W] in GPU buffers.
  // Writes every parameter gradient into `grads`, the pose gradient (se(3), translation first)
  // and the per-Gaussian screen-space gradient norm. With `accumulate`, gradients and the
  // screen-gradient norms are added to what `grads` and grad2d_norm() hold (several renders in
  // one step); the pose gradient is always this render's alone.
  void backward(const RenderState& state, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                const gpu::Buffer& v_alpha, GaussianBuffers& grads, bool accumulate = false);

  // The backward of several renders in one submit, their gradients added into `grads` and
  // grad2d_norm() in order (the first overwrites); returns each render's pose gradient.
  std::vector<std::array<float, 6>> backward(const std::vector<const RenderState*>& states,
                                             const GaussianBuffers& params,
                                             const std::vector<const gpu::Buffer*>& v_rgb, const gpu::Buffer& v_alpha,
                                             GaussianBuffers& grads);
  // Of the last backward (the last render's of a batch).
  std::array<float, 6> pose_gradient() const;
  const gpu::Buffer& grad2d_norm() const { return grad2d_norm_; }
  // Stage times (ms) of the last forward and backward, in order.
  const std::vector<std::pair<std::string, double>>& stage_ms() const { return stage_ms_; }

 private:
  void set_pc(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings, RenderState& st) const;
  void ensure_forward_buffers(RenderState& st) const;
  void record_project(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings,
                      RenderState& st);
  void set_count(RenderState& st, uint32_t isects) const;
  void record_raster(RenderState& st);
  void check_backward(const RenderState& st, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                      const gpu::Buffer& v_alpha, const GaussianBuffers& grads) const;
  void ensure_backward_buffers(size_t n, uint64_t isects);
  void record_backward(const RenderState& st, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                       const gpu::Buffer& v_alpha, GaussianBuffers& grads, bool accumulate, uint32_t pose_slot);
  void drop_backward_stages();
  gpu::Context& ctx_;
  gpu::Commands cmd_;
  PrefixSum scan_;
  RadixSort sort_;
  // Per-intersection gradients of the backward pass: (mean xy, conic xy) and (conic z, opacity,
  // red, green) as vec4 planes, blue as a float plane (splat_layout.h), a buffer each:
  // GPU-assisted validation checks accesses against whole buffers.
  std::vector<gpu::Buffer> isect_grad_;
  gpu::Buffer grad2d_norm_, pose_partial_;
  gpu::Buffer poses_;                      // a backward's pose gradients, one per render (pose_reduce's slots)
  uint32_t last_pose_ = 0;                 // the last render's slot in poses_
  gpu::Buffer counts_;                     // a batch's intersection counts, one per render: one download
  bool subgroup_reduce_ = false;           // backward: subgroupAdd before the shared add
  std::string block_suffix_;               // "" (one pixel per invocation) or "_block" (RasterKernels::block)
  std::string block_bwd_suffix() const;    // the block backward's build for this device's subgroups
  uint32_t pose_partials(size_t n) const;  // project_bwd's pose partials for n Gaussians
  std::vector<std::pair<std::string, double>> stage_ms_;
};

}  // namespace evflow
