#version 450
// The residual loss of one non-middle frame i: d = (F_i - F_N) - R_i per element; the group's sum
// of d^2 into partials[partial_base + group]; grad_i += grad_scale * 2d, grad_N -= grad_scale * 2d
// (frames are recorded one dispatch after another, so grad_N's read-modify-write never races).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kResidualBindFrame) readonly buffer Frame { float frame[]; };
layout(std430, binding = kResidualBindMid) readonly buffer Mid { float mid[]; };
layout(std430, binding = kResidualBindPrior) readonly buffer Prior { float prior[]; };
layout(std430, binding = kResidualBindGradFrame) buffer GradFrame { float grad_frame[]; };
layout(std430, binding = kResidualBindGradMid) buffer GradMid { float grad_mid[]; };
layout(std430, binding = kResidualBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { ResidualPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  float e = 0.0;
  if (i < pc.count) {
    float d = (frame[i] - mid[i]) - prior[i];
    e = d * d;
    float g = pc.grad_scale * 2.0 * d;
    grad_frame[i] += g;
    grad_mid[i] -= g;
  }
  vec4 total = loss_group_sum(vec4(e, 0.0, 0.0, 0.0));
  if (gl_LocalInvocationIndex == 0u) partials[pc.partial_base + evf_linear_group()] = total;
}
