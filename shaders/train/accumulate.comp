#version 450
// y = (accumulate ? y : 0) + scale * x: the mean of the virtual frames of an exposure (the
// blurry image model). Four elements per invocation through vec4 accesses (CPU drivers loop over
// the lanes for every storage access), one by one only for the last 1-3; x is read as texels
// (straight-line code on lavapipe; a buffer is a whole number of vec4s, gpu/buffer.h).
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kAccumulateGroupSize) in;
layout(binding = kTrainAccumulateBindX) uniform samplerBuffer X;
layout(std430, binding = kTrainAccumulateBindY) buffer Y { vec4 y[]; };
layout(push_constant) uniform PC { AccumulatePC pc; };
void main() {
  uint i = evf_linear_invocation(kAccumulateGroupSize);
  if (i * 4u >= pc.n) return;
  if (i * 4u + 4u <= pc.n) {
    y[i] = (pc.accumulate != 0u ? y[i] : vec4(0.0)) + pc.scale * texelFetch(X, int(i));
    return;
  }
  for (uint c = 0u; i * 4u + c < pc.n; ++c) y[i][c] = (pc.accumulate != 0u ? y[i][c] : 0.0) + pc.scale * texelFetch(X, int(i))[c];
}
