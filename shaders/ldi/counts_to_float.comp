#version 450
// Event counts to the network's float input, in place (ldi_layout.h, LdiCountPC).
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiCountBindValues) buffer Values { uint values[]; };
layout(push_constant) uniform PC { LdiCountPC pc; };

void main() {
  uint i = evf_linear_invocation(kLdiGroupSize);
  if (i >= pc.n) return;
  values[i] = floatBitsToUint(float(values[i]));
}
