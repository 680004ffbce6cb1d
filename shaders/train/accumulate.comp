#version 450
// y = (accumulate ? y : 0) + scale * x, one invocation per element: the mean of the virtual
// frames of an exposure (the blurry image model).
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kAccumulateGroupSize) in;
layout(std430, binding = kTrainAccumulateBindX) readonly buffer X { float x[]; };
layout(std430, binding = kTrainAccumulateBindY) buffer Y { float y[]; };
layout(push_constant) uniform PC { AccumulatePC pc; };
void main() {
  uint i = evf_linear_invocation(kAccumulateGroupSize);
  if (i >= pc.n) return;
  y[i] = (pc.accumulate != 0u ? y[i] : 0.0) + pc.scale * x[i];
}
