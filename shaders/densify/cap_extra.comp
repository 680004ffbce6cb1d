#version 450
// Cap, step 1: the extra rows of the Gaussians in descending-gradient order.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kCapExtraBindIds) readonly buffer Ids { uint sorted_ids[]; };
layout(std430, binding = kCapExtraBindDecision) readonly buffer Decision { uint decision[]; };
layout(std430, binding = kCapExtraBindExtra) writeonly buffer Extra { uint sorted_extra[]; };
layout(push_constant) uniform PC { CapPC pc; };

void main() {
  uint j = evf_linear_invocation(kDensifyGroupSize);
  if (j >= pc.count) return;
  sorted_extra[j] = extra_rows(decision[sorted_ids[j]]);
}
