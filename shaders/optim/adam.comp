#version 450
// One Adam step over a parameter group (see optim_layout.h for the update).
#extension GL_GOOGLE_include_directive : require
#include "optim/optim_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kOptimGroupSize) in;
layout(std430, binding = kAdamBindParam) buffer Param { float param[]; };
layout(std430, binding = kAdamBindGrad) readonly buffer Grad { float grad[]; };
layout(std430, binding = kAdamBindM) buffer M { float exp_avg[]; };
layout(std430, binding = kAdamBindV) buffer V { float exp_avg_sq[]; };
layout(push_constant) uniform PC { AdamPC pc; };

void main() {
  uint i = evf_linear_invocation(kOptimGroupSize);
  if (i >= pc.count) return;
  float g = grad[i];
  float m = pc.beta1 * exp_avg[i] + pc.one_minus_beta1 * g;
  float v = pc.beta2 * exp_avg_sq[i] + pc.one_minus_beta2 * (g * g);
  exp_avg[i] = m;
  exp_avg_sq[i] = v;
  param[i] -= pc.step_size * m / (sqrt(v) * pc.inv_sqrt_bc2 + pc.eps);
}
