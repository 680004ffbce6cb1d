#version 450
// Per Gaussian: prune / keep / clone / split decision (3DGS rules, docs/density_control.md),
// its output row count, and (with a cap) the sort key of its growth.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kDecideBindLogScales) readonly buffer LogScales { float log_scales[]; };
layout(std430, binding = kDecideBindOpacity) readonly buffer Opacity { float opacity_logits[]; };
layout(std430, binding = kDecideBindGradSum) readonly buffer GradSum { float grad_sum[]; };
layout(std430, binding = kDecideBindVisCount) readonly buffer VisCount { uint vis_count[]; };
layout(std430, binding = kDecideBindMaxRadius) readonly buffer MaxRadius { float max_radius[]; };
layout(std430, binding = kDecideBindDecision) writeonly buffer Decision { uint decision[]; };
layout(std430, binding = kDecideBindOutCount) writeonly buffer OutCount { uint out_count[]; };
layout(std430, binding = kDecideBindKeys) writeonly buffer Keys { uint sort_keys[]; };
layout(std430, binding = kDecideBindIds) writeonly buffer Ids { uint sort_ids[]; };
layout(push_constant) uniform PC { DecidePC pc; };

void main() {
  uint g = evf_linear_invocation(kDensifyGroupSize);
  if (g >= pc.count) return;
  float max_ls = max3(vec3(log_scales[3 * g], log_scales[3 * g + 1], log_scales[3 * g + 2]));
  float smax = exp(max_ls);
  float child_smax = exp(max_ls - pc.log_split_div);
  uint n = vis_count[g];
  float mean_grad = n > 0u ? grad_sum[g] / float(n) : 0.0;

  bool low = opacity_logits[g] < pc.min_opacity_logit;
  bool big_screen = pc.prune_big != 0u && max_radius[g] > pc.max_screen_radius;
  bool big_world = pc.prune_big != 0u && smax > pc.max_world_scale;
  bool child_big_world = pc.prune_big != 0u && child_smax > pc.max_world_scale;

  uint dec = 0u;
  if (low) dec |= kDecLowOpacity;
  if (big_screen) dec |= kDecBigScreen;
  if (big_world) dec |= kDecBigWorld;
  if (!(low || big_screen || big_world)) dec |= kDecKeep;
  bool candidate = mean_grad > pc.grad_threshold;
  if (candidate) {
    if (smax <= pc.clone_max_scale) {
      // The copy is new (screen radius 0): only opacity and world size can prune it.
      if (!(low || big_world)) dec |= kDecClone;
    } else {
      if (!(low || child_big_world)) dec |= kDecSplit;
    }
  }
  uint extra = extra_rows(dec);
  if (pc.capped == 0u) {
    if (extra > 0u) dec |= kDecGrown;
  } else {
    // Descending gradient, ties by index (stable sort); non-candidates last.
    sort_keys[g] = extra > 0u ? ~floatBitsToUint(mean_grad) : 0xFFFFFFFFu;
    sort_ids[g] = g;
  }
  decision[g] = dec;
  out_count[g] = out_rows(dec);
}
