#version 450
// y = (accumulate ? y : 0) + scale * x: the mean of the virtual frames of an exposure (the
// blurry image model). Four elements per invocation through vec4 accesses (CPU drivers loop over
// the lanes for every access), one by one only for the last 1-3.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kAccumulateGroupSize) in;
layout(std430, binding = kTrainAccumulateBindX) readonly buffer X { vec4 x[]; };
layout(std430, binding = kTrainAccumulateBindY) buffer Y { vec4 y[]; };
layout(push_constant) uniform PC { AccumulatePC pc; };
void main() {
  uint i = evf_linear_invocation(kAccumulateGroupSize);
  if (i * 4u >= pc.n) return;
  if (i * 4u + 4u <= pc.n) {
    y[i] = (pc.accumulate != 0u ? y[i] : vec4(0.0)) + pc.scale * x[i];
    return;
  }
  for (uint c = 0u; i * 4u + c < pc.n; ++c) y[i][c] = (pc.accumulate != 0u ? y[i][c] : 0.0) + pc.scale * x[i][c];
}
