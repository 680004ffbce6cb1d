#version 450
// relu backward (nn_layout.h, PointwisePC): dx = dy * relu'(x), from the forward's output y;
// written, or added with pc.accumulate.
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kNnGroupSize) in;
layout(std430, binding = kActBwdBindY) readonly buffer Y { float y[]; };
layout(std430, binding = kActBwdBindDy) readonly buffer Dy { float dy[]; };
layout(std430, binding = kActBwdBindDx) buffer Dx { float dx[]; };
layout(push_constant) uniform PC { PointwisePC pc; };
#include "nn/pointwise_math.glsl"

void main() {
  uint i = evf_linear_invocation(kNnGroupSize);
  if (i >= pc.count) return;
  float g = dy[i] * nn_relu_slope(y[i]);
  dx[i] = pc.accumulate != 0u ? dx[i] + g : g;
}
