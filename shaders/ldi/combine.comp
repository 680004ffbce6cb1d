#version 450
// Frame i of the LDI (ldi_layout.h, LdiCombinePC): its double integral E from the two sides'
// network outputs, and the sharp frame C = B / E of the blurry crop, one invocation per pixel.
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiCombineBindSides) readonly buffer Sides { float sides[]; };
layout(std430, binding = kLdiCombineBindBlurry) readonly buffer Blurry { float blurry[]; };
layout(std430, binding = kLdiCombineBindIntegral) writeonly buffer Integral { float integral[]; };
layout(std430, binding = kLdiCombineBindFrames) writeonly buffer Frames { float frames[]; };
layout(push_constant) uniform PC { LdiCombinePC pc; };
#include "ldi/ldi_math.glsl"

float ldi_side(uint plane, uint n, uint p) { return plane == kLdiNoSide ? 0.0 : sides[plane * n + p]; }

void main() {
  uint p = evf_linear_invocation(kLdiGroupSize), n = pc.pixels;
  if (p >= n) return;
  float e = ldi_integral(ldi_side(pc.before, n, p), ldi_side(pc.after, n, p));
  integral[pc.frame * n + p] = e;
  for (uint c = 0u; c < 3u; ++c) frames[c * n + p] = ldi_frame(blurry[c * n + p], e);
}
