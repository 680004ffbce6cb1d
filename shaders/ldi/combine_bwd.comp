#version 450
// The backward of ldi/combine for frame i (ldi_layout.h, LdiCombinePC): the gradients of the
// two sides' network outputs, from the frame's gradient (kLdiFromFrames, with the anchor's
// regression where pc.anchor is not 0) or from the regression of log E to a target integral
// (kLdiFromTarget), one invocation per pixel.
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiCombineBwdBindSides) readonly buffer Sides { float sides[]; };
layout(std430, binding = kLdiCombineBwdBindBlurry) readonly buffer Blurry { float blurry[]; };
layout(std430, binding = kLdiCombineBwdBindGrads) readonly buffer Grads { float grads[]; };
layout(std430, binding = kLdiCombineBwdBindSideGrads) writeonly buffer SideGrads { float side_grads[]; };
layout(std430, binding = kLdiCombineBwdBindAnchor) readonly buffer Anchor { float anchor[]; };
layout(push_constant) uniform PC { LdiCombinePC pc; };
#include "ldi/ldi_math.glsl"

float ldi_side(uint plane, uint n, uint p) { return plane == kLdiNoSide ? 0.0 : sides[plane * n + p]; }

void main() {
  uint p = evf_linear_invocation(kLdiGroupSize), n = pc.pixels;
  if (p >= n) return;
  float a = ldi_side(pc.before, n, p), b = ldi_side(pc.after, n, p);
  float e = ldi_integral(a, b), g_e = 0.0;
  if (pc.mode == kLdiFromTarget) {
    g_e = pc.scale * ldi_regression_bwd(e, grads[pc.frame * n + p]);
  } else {
    for (uint c = 0u; c < 3u; ++c) g_e += ldi_frame_bwd(blurry[c * n + p], e, grads[c * n + p]);
    g_e *= pc.scale;
    if (pc.anchor != 0.0) g_e += pc.anchor * ldi_regression_bwd(e, anchor[pc.frame * n + p]);
  }
  float g_x = ldi_integral_bwd(a, b, g_e);
  if (pc.before != kLdiNoSide) side_grads[pc.before * n + p] = pc.w1 * g_x;
  if (pc.after != kLdiNoSide) side_grads[pc.after * n + p] = pc.w2 * g_x;
}
