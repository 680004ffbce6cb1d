#version 450
// Cap, step 1: the extra rows of the Gaussians in descending-gradient order.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = 128) in;
layout(std430, binding = 0) readonly buffer Ids { uint sorted_ids[]; };
layout(std430, binding = 1) readonly buffer Decision { uint decision[]; };
layout(std430, binding = 2) writeonly buffer Extra { uint sorted_extra[]; };
layout(push_constant) uniform PC { CapPC pc; };

void main() {
  uint j = evf_linear_invocation(kDensifyGroupSize);
  if (j >= pc.count) return;
  sorted_extra[j] = extra_rows(decision[sorted_ids[j]]);
}
