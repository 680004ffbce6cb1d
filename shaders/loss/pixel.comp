#version 450
// Per-pixel loss e = |A-B| (or (A-B)^2 with kLossPixelL2): workgroup sums into partials, and
// (kLossWriteGrad) grad (+)= grad_scale * de/dA.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kPixelLossBindA) readonly buffer A { float img_a[]; };
layout(std430, binding = kPixelLossBindB) readonly buffer B { float img_b[]; };
layout(std430, binding = kPixelLossBindGrad) buffer Grad { float grad[]; };
layout(std430, binding = kPixelLossBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { PixelPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  float e = 0.0;
  if (i < pc.count) {
    float diff = img_a[i] - img_b[i];
    bool l2 = (pc.flags & kLossPixelL2) != 0u;
    e = l2 ? diff * diff : abs(diff);
    if ((pc.flags & kLossWriteGrad) != 0u) {
      float g = pc.grad_scale * (l2 ? 2.0 * diff : sign(diff));
      if ((pc.flags & kLossAccumulate) != 0u) g += grad[i];
      grad[i] = g;
    }
  }
  vec4 total = loss_group_sum(vec4(e, 0.0, 0.0, 0.0));
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
