// Adaptive density control: push constants and codes shared by engine/densify (C++) and
// shaders/densify (GLSL). See docs/density_control.md.
#ifndef EVF_DENSIFY_LAYOUT_H
#define EVF_DENSIFY_LAYOUT_H
#include "common/shared_prelude.h"
#include "common/camera_layout.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kDensifyGroupSize, 128u)
EVF_CONST(uint, kDensifyNoSource, 0xFFFFFFFFu)  // == kAdamNoSource: zero optimizer state

// Decision word per Gaussian (densify/decide), bit flags:
EVF_CONST(uint, kDecKeep, 1u)       // the original survives when it does not grow
EVF_CONST(uint, kDecClone, 2u)      // clone candidate whose copy survives pruning
EVF_CONST(uint, kDecSplit, 4u)      // split candidate whose two children survive pruning
EVF_CONST(uint, kDecGrown, 8u)      // growth granted (always, unless the cap refused it)
EVF_CONST(uint, kDecLowOpacity, 16u)  // pruned: opacity below min_opacity
EVF_CONST(uint, kDecBigScreen, 32u)   // pruned: max screen radius above the limit
EVF_CONST(uint, kDecBigWorld, 64u)    // pruned: max scale above the world limit

// Row code per new Gaussian (densify/index): 0 = copy of the source row, 1 / 2 = first /
// second split child of the source row.
EVF_CONST(uint, kRowCopy, 0u)
EVF_CONST(uint, kRowChild0, 1u)

// densify/accumulate, one invocation per Gaussian:
//   grad_sum[g] += grad2d_norm[g] * grad_scale and vis_count[g] += 1 when visible;
//   max_radius[g] = max(max_radius[g], radius) when the camera is used (use_camera != 0).
// visible = the projected Gaussian meets the image (use_camera) or grad2d_norm[g] > 0.
struct AccumulatePC {
  CameraPC cam;
  uint count;
  uint use_camera;
  float grad_scale;
  uint pad0;
};

// densify/decide, one invocation per Gaussian.
struct DecidePC {
  uint count;
  float grad_threshold;     // grow where grad_sum / vis_count > this
  float clone_max_scale;    // clone where max exp(log_scale) <= this, else split
  float min_opacity_logit;  // prune where opacity logit < logit(min_opacity)
  float max_screen_radius;  // prune where max_radius > this (prune_big != 0)
  float max_world_scale;    // prune where max exp(log_scale) > this (prune_big != 0)
  float log_split_div;      // children: log_scale - log_split_div
  uint prune_big;
  uint capped;              // 1: write sort keys for the cap, else grant every growth
  uint pad0, pad1, pad2;
};

// densify/cap_extra (j < count): sorted_extra[j] = extra rows of Gaussian sorted_ids[j].
// densify/cap_grant (j < count): grant growth of sorted_ids[j] when
//   scan[j] + extra <= budget, budget = max_total - base_total (base_total read on the GPU).
struct CapPC {
  uint count;
  uint max_total;
  uint pad0, pad1;
};

// densify/index (g < count): writes rows offsets[g] .. offsets[g+1] of param_src, state_src, code.
// densify/geometry (r < rows): new means and log-scales (split children sampled from the parent).
struct EmitPC {
  uint count;        // old Gaussians
  uint rows;         // new Gaussians
  uint seed;
  float log_split_div;
  float max_sigma;   // children's offsets are truncated to this Mahalanobis radius
  uint pad0, pad1, pad2;
};

// densify/opacity_reset (g < count): logit = min(logit, max_logit); mask[g] = 1.
struct ResetPC {
  uint count;
  float max_logit;
  uint pad0, pad1;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// densify/accumulate
EVF_BIND(kDensifyAccumulateBindGrad2d, 0u, Grad2d)
EVF_BIND(kDensifyAccumulateBindMeans, 1u, Means)
EVF_BIND(kDensifyAccumulateBindLogScales, 2u, LogScales)
EVF_BIND(kDensifyAccumulateBindQuats, 3u, Quats)
EVF_BIND(kDensifyAccumulateBindGradSum, 4u, GradSum)
EVF_BIND(kDensifyAccumulateBindVisCount, 5u, VisCount)
EVF_BIND(kDensifyAccumulateBindMaxRadius, 6u, MaxRadius)
// densify/cap_extra
EVF_BIND(kCapExtraBindIds, 0u, Ids)
EVF_BIND(kCapExtraBindDecision, 1u, Decision)
EVF_BIND(kCapExtraBindExtra, 2u, Extra)
// densify/cap_grant
EVF_BIND(kCapGrantBindIds, 0u, Ids)
EVF_BIND(kCapGrantBindExtra, 1u, Extra)
EVF_BIND(kCapGrantBindExtraScan, 2u, ExtraScan)
EVF_BIND(kCapGrantBindBaseScan, 3u, BaseScan)
EVF_BIND(kCapGrantBindDecision, 4u, Decision)
EVF_BIND(kCapGrantBindOutCount, 5u, OutCount)
// densify/decide
EVF_BIND(kDecideBindLogScales, 0u, LogScales)
EVF_BIND(kDecideBindOpacity, 1u, Opacity)
EVF_BIND(kDecideBindGradSum, 2u, GradSum)
EVF_BIND(kDecideBindVisCount, 3u, VisCount)
EVF_BIND(kDecideBindMaxRadius, 4u, MaxRadius)
EVF_BIND(kDecideBindDecision, 5u, Decision)
EVF_BIND(kDecideBindOutCount, 6u, OutCount)
EVF_BIND(kDecideBindKeys, 7u, Keys)
EVF_BIND(kDecideBindIds, 8u, Ids)
// densify/geometry
EVF_BIND(kDensifyGeometryBindMeans, 0u, Means)
EVF_BIND(kDensifyGeometryBindLogScales, 1u, LogScales)
EVF_BIND(kDensifyGeometryBindQuats, 2u, Quats)
EVF_BIND(kDensifyGeometryBindParamSrc, 3u, ParamSrc)
EVF_BIND(kDensifyGeometryBindCode, 4u, Code)
EVF_BIND(kDensifyGeometryBindNewMeans, 5u, NewMeans)
EVF_BIND(kDensifyGeometryBindNewLogScales, 6u, NewLogScales)
// densify/index
EVF_BIND(kDensifyIndexBindDecision, 0u, Decision)
EVF_BIND(kDensifyIndexBindOffsets, 1u, Offsets)
EVF_BIND(kDensifyIndexBindParamSrc, 2u, ParamSrc)
EVF_BIND(kDensifyIndexBindStateSrc, 3u, StateSrc)
EVF_BIND(kDensifyIndexBindCode, 4u, Code)
// densify/opacity_reset
EVF_BIND(kOpacityResetBindOpacity, 0u, Opacity)
EVF_BIND(kOpacityResetBindMask, 1u, Mask)

EVF_NAMESPACE_END
#endif
