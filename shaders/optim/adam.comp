#version 450
// One Adam step over a parameter group (see optim_layout.h for the update). Each invocation
// updates four consecutive elements through vec4 accesses: on CPU drivers every buffer access is
// a loop over the SIMD lanes, so one vec4 access instead of four float ones quarters that work.
#extension GL_GOOGLE_include_directive : require
#include "optim/optim_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kOptimGroupSize) in;
layout(std430, binding = kAdamBindParam) buffer Param { vec4 param[]; };
layout(std430, binding = kAdamBindGrad) readonly buffer Grad { vec4 grad[]; };
layout(std430, binding = kAdamBindM) buffer M { vec4 exp_avg[]; };
layout(std430, binding = kAdamBindV) buffer V { vec4 exp_avg_sq[]; };
layout(push_constant) uniform PC { AdamPC pc; };

void main() {
  uint i = evf_linear_invocation(kOptimGroupSize);
  if (i * 4u >= pc.count) return;
  if (i * 4u + 4u <= pc.count) {
    vec4 g = grad[i];
    vec4 m = pc.beta1 * exp_avg[i] + pc.one_minus_beta1 * g;
    vec4 v = pc.beta2 * exp_avg_sq[i] + pc.one_minus_beta2 * (g * g);
    exp_avg[i] = m;
    exp_avg_sq[i] = v;
    param[i] -= pc.step_size * m / (sqrt(v) * pc.inv_sqrt_bc2 + pc.eps);
    return;
  }
  for (uint k = 0u; i * 4u + k < pc.count; ++k) {  // the group's last 1-3 elements, one by one
    float g = grad[i][k];
    float m = pc.beta1 * exp_avg[i][k] + pc.one_minus_beta1 * g;
    float v = pc.beta2 * exp_avg_sq[i][k] + pc.one_minus_beta2 * (g * g);
    exp_avg[i][k] = m;
    exp_avg_sq[i][k] = v;
    param[i][k] -= pc.step_size * m / (sqrt(v) * pc.inv_sqrt_bc2 + pc.eps);
  }
}
