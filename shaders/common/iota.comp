#version 450
// values[i] = i + offset for i < n. One invocation per element; the grid may span y when there
// are more than 65,535 workgroups.
#extension GL_GOOGLE_include_directive : require
#include "common/common_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kIotaGroupSize) in;
layout(std430, binding = kIotaBindValues) writeonly buffer Values { uint values[]; };
layout(push_constant) uniform PC { uint n; uint offset; } pc;
void main() {
  uint i = evf_linear_invocation(kIotaGroupSize);
  if (i < pc.n) values[i] = i + pc.offset;
}
