#version 450
// Opacity reset: logit = min(logit, max_logit); mask[g] = 1 (for the optimizer-state reset).
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kOpacityResetBindOpacity) buffer Opacity { float opacity_logits[]; };
layout(std430, binding = kOpacityResetBindMask) writeonly buffer Mask { uint mask[]; };
layout(push_constant) uniform PC { ResetPC pc; };

void main() {
  uint g = evf_linear_invocation(kDensifyGroupSize);
  if (g >= pc.count) return;
  float x = opacity_logits[g];
  opacity_logits[g] = x > pc.max_logit ? pc.max_logit : x;  // NaN stays NaN
  mask[g] = 1u;
}
