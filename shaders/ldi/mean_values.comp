#version 450
// One value as the scaled sum of others, in a fixed order (ldi_layout.h, LdiMeanPC): a term's
// value from its per-frame values.
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
layout(local_size_x = 1) in;
layout(std430, binding = kLdiMeanBindSrc) readonly buffer Src { float src[]; };
layout(std430, binding = kLdiMeanBindValues) buffer Values { float values[]; };
layout(push_constant) uniform PC { LdiMeanPC pc; };

void main() {
  float s = 0.0;
  for (uint k = 0u; k < pc.count; ++k) s += src[pc.first + k * pc.stride];
  values[pc.dst] = pc.scale * s;
}
