#version 450
// sigmoid forward (nn_layout.h, PointwisePC): y = sigmoid(x), one invocation per value.
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kNnGroupSize) in;
layout(std430, binding = kActFwdBindX) readonly buffer X { float x[]; };
layout(std430, binding = kActFwdBindY) writeonly buffer Y { float y[]; };
layout(push_constant) uniform PC { PointwisePC pc; };
#include "nn/pointwise_math.glsl"

void main() {
  uint i = evf_linear_invocation(kNnGroupSize);
  if (i < pc.count) y[i] = nn_sigmoid(x[i]);
}
