#version 450
// Row gather: dst[r * width + k] = src[index[r] * width + k], zero for index kOptimNoSource.
#extension GL_GOOGLE_include_directive : require
#include "optim/optim_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kOptimGroupSize) in;
layout(std430, binding = kOptimGatherBindSrc) readonly buffer Src { float src[]; };
layout(std430, binding = kOptimGatherBindDst) writeonly buffer Dst { float dst[]; };
layout(std430, binding = kOptimGatherBindIndex) readonly buffer Index { uint index[]; };
layout(push_constant) uniform PC { RowsPC pc; };

void main() {
  uint i = evf_linear_invocation(kOptimGroupSize);
  if (i >= pc.rows * pc.width) return;
  uint r = i / pc.width;
  uint k = i - r * pc.width;
  uint s = index[r];
  dst[i] = s == kOptimNoSource ? 0.0 : src[s * pc.width + k];
}
