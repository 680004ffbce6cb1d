// Adaptive density control (3DGS): clone, split, prune and opacity reset on the GPU
// (docs/density_control.md). Statistics accumulate per Gaussian after every backward;
// refine() decides per Gaussian in a kernel, scans the row counts, reads back one scalar (the
// new count), then gathers every parameter buffer and the Adam state into freshly sized
// buffers. Everything is deterministic: no float atomics, fixed-order scans, hash-based RNG.
#pragma once
#include <cstdint>
#include <string>

#include "gpu/commands.h"
#include "optim/adam.h"
#include "scan/prefix_sum.h"
#include "sort/radix_sort.h"
#include "splat/rasterizer.h"

namespace evflow {

struct DensityConfig {
  // Schedule (steps are 1-based, as Trainer::current_step() after step()).
  uint32_t refine_from = 500;     // first refinement step
  uint32_t refine_until = 15000;  // refinement while step < refine_until (3DGS densify_until_iter)
  uint32_t refine_every = 100;
  uint32_t reset_every = 3000;  // opacity reset period (0 = never)
  // Rules.
  float grad_threshold = 2e-4f;     // grow where the mean screen-space gradient > this
  float percent_dense = 0.01f;      // clone where max scale <= percent_dense * extent, else split
  float split_divisor = 1.6f;       // children's scale = parent's / split_divisor
  float split_max_sigma = 3.0f;     // children's offsets truncated to this Mahalanobis radius
  float min_opacity = 0.005f;       // prune where opacity < this
  float max_screen_radius = 20.0f;  // after the first reset: prune where max radius (px) > this (0: off)
  float max_world_scale = 0.1f;     // after the first reset: prune where max scale > this * extent (0: off)
  float reset_opacity = 0.01f;      // opacity reset: opacity = min(opacity, this)
  uint32_t max_gaussians = 0;       // cap on the count after growth (0 = none)
  uint32_t seed = 0;                // split sampling

  bool refine_at(uint32_t step) const {
    return refine_every && step >= refine_from && step < refine_until && step % refine_every == 0;
  }
  // 3DGS resets opacity every reset_every steps (while refining), and never at step 0.
  bool reset_at(uint32_t step) const {
    return reset_every && step > 0 && step < refine_until && step % reset_every == 0;
  }
  // Screen- and world-size pruning starts after the first opacity reset (3DGS: iteration > reset).
  bool prune_big_at(uint32_t step) const { return reset_every && step > reset_every; }
};

// Per-Gaussian statistics between refinements: sum of screen-gradient norms, visibility count,
// largest screen radius (pixels; only with a camera).
class DensityStats {
 public:
  explicit DensityStats(gpu::Context& ctx);
  // Sizes the statistics for `count` Gaussians and zeroes them (recorded on cmd).
  void reset(gpu::Commands& cmd, uint32_t count);
  // After a backward, without a camera: visible = grad2d_norm > 0; no screen radius.
  void accumulate(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, float grad_scale = 1.0f);
  // After a backward, with the camera of that render: visible = the projected Gaussian meets the
  // image (3DGS: radii > 0); the screen radius ceil(3 sqrt(lambda_max)) feeds the maximum.
  // grad_scale multiplies the pixel-space norm: 0.5 * width gives 3DGS's NDC-scaled gradient.
  void accumulate(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, const GaussianBuffers& params, const Camera& cam,
                  float grad_scale = 1.0f);
  uint32_t count() const { return count_; }
  const gpu::Buffer& grad_sum() const { return grad_sum_; }
  const gpu::Buffer& vis_count() const { return vis_count_; }
  const gpu::Buffer& max_radius() const { return max_radius_; }

 private:
  gpu::Context& ctx_;
  uint32_t count_ = 0;
  gpu::Buffer grad_sum_, vis_count_, max_radius_;
};

struct RefineResult {
  uint32_t before = 0;
  uint32_t after = 0;
};

class DensityControl {
 public:
  DensityControl(gpu::Context& ctx, DensityConfig cfg = {});
  const DensityConfig& config() const { return cfg_; }
  DensityConfig& config() { return cfg_; }

  // One refinement: prune / clone / split by the statistics, then:
  //  - params and grads are replaced (move-assigned, same objects) by buffers of the new count;
  //    grads are zero; the Adam groups named means, log_scales, quats, opacity_logits, sh0..sh3
  //    are gathered (state follows its Gaussian; clones and split children start at zero) and
  //    rebound to the new buffers; other groups are left alone;
  //  - stats are reset to the new count.
  // Submits cmd twice (everything recorded before is submitted too). `extent`: scene extent;
  // `prune_big`: apply the screen/world size pruning (DensityConfig::prune_big_at(step)).
  RefineResult refine(gpu::Commands& cmd, GaussianBuffers& params, GaussianBuffers& grads, Adam& adam,
                      DensityStats& stats, float extent, bool prune_big);
  // Opacity reset: logits clamped to <= logit(reset_opacity), both Adam moments of the
  // opacity_logits group zeroed (when the group exists). Recorded on cmd, not submitted.
  void reset_opacity(gpu::Commands& cmd, GaussianBuffers& params, Adam& adam);

  // Decision words of the last refine (densify_layout.h kDec* bits), one per old Gaussian.
  const gpu::Buffer& decisions() const { return decision_; }
  uint32_t refinements() const { return refinements_; }

 private:
  gpu::Context& ctx_;
  DensityConfig cfg_;
  PrefixSum scan_;
  RadixSort sort_;
  uint32_t refinements_ = 0;
  gpu::Buffer decision_, out_count_, offsets_, base_offsets_, keys_, ids_, sorted_extra_, extra_offsets_;
  gpu::Buffer param_src_, state_src_, row_code_, mask_;
};

}  // namespace evflow
