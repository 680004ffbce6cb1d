#version 450
// One Adam step over a parameter group (see optim_layout.h for the update). Each invocation
// updates four consecutive elements through vec4 accesses: on CPU drivers every buffer access is
// a loop over the SIMD lanes, so one vec4 access instead of four float ones quarters that work.
// It reads the gradient, and the parameter and moments it updates, through texel views (the
// parameter and moments: views of the buffers it writes, each element read and then written by
// its own invocation alone): on lavapipe a texel fetch is straight-line code.
#extension GL_GOOGLE_include_directive : require
#include "optim/optim_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kOptimGroupSize) in;
layout(std430, binding = kAdamBindParam) writeonly buffer Param { vec4 param[]; };
layout(std430, binding = kAdamBindM) writeonly buffer M { vec4 exp_avg[]; };
layout(std430, binding = kAdamBindV) writeonly buffer V { vec4 exp_avg_sq[]; };
layout(binding = kAdamBindGrad) uniform samplerBuffer Grad;
layout(binding = kAdamBindParamIn) uniform samplerBuffer ParamIn;
layout(binding = kAdamBindMIn) uniform samplerBuffer MIn;
layout(binding = kAdamBindVIn) uniform samplerBuffer VIn;
layout(push_constant) uniform PC { AdamPC pc; };

void main() {
  uint i = evf_linear_invocation(kOptimGroupSize);
  if (i * 4u >= pc.count) return;
  if (i * 4u + 4u <= pc.count) {
    vec4 g = texelFetch(Grad, int(i));
    vec4 m = pc.beta1 * texelFetch(MIn, int(i)) + pc.one_minus_beta1 * g;
    vec4 v = pc.beta2 * texelFetch(VIn, int(i)) + pc.one_minus_beta2 * (g * g);
    exp_avg[i] = m;
    exp_avg_sq[i] = v;
    param[i] = texelFetch(ParamIn, int(i)) - pc.step_size * m / (sqrt(v) * pc.inv_sqrt_bc2 + pc.eps);
    return;
  }
  for (uint k = 0u; i * 4u + k < pc.count; ++k) {  // the group's last 1-3 elements, one by one
    float g = texelFetch(Grad, int(i))[k];
    float m = pc.beta1 * texelFetch(MIn, int(i))[k] + pc.one_minus_beta1 * g;
    float v = pc.beta2 * texelFetch(VIn, int(i))[k] + pc.one_minus_beta2 * (g * g);
    exp_avg[i][k] = m;
    exp_avg_sq[i][k] = v;
    param[i][k] = texelFetch(ParamIn, int(i))[k] - pc.step_size * m / (sqrt(v) * pc.inv_sqrt_bc2 + pc.eps);
  }
}
