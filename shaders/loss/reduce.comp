#version 450
// Fixed-order sum of the per-workgroup partials (one workgroup: invocation t sums partials
// t, t + 256, ... in order, then a tree in shared memory), then up to four affine outputs
// out[dst + j] = dot(coeff_j, s) + offset_j, optionally -10 log10(.) (PSNR). Workgroup c: column c
// (loss_layout.h).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
layout(local_size_x = kReduceGroupSize) in;
layout(std430, binding = kReduceBindPartials) readonly buffer Partials { vec4 partials[]; };
layout(std430, binding = kReduceBindOut) buffer Out { float values[]; };
layout(push_constant) uniform PC { ReducePC pc; };
shared vec4 red[kReduceGroupSize];

void main() {
  uint lid = gl_LocalInvocationIndex, first = gl_WorkGroupID.x * pc.n_partials;
  vec4 s = vec4(0.0);
  for (uint g = lid; g < pc.n_partials; g += kReduceGroupSize) s += partials[first + g];
  red[lid] = s;
  barrier();
  // Each level's add as a loop of one trip in the invocations that add and none elsewhere: on CPU
  // drivers an `if` skips nothing, and every SIMD vector would run the masked-off accesses as
  // loops over its lanes.
  for (uint k = kReduceGroupSize / 2u; k > 0u; k >>= 1u) {
    for (uint t = lid < k ? 1u : 0u; t > 0u; --t) red[lid] += red[lid + k];
    barrier();
  }
  if (lid < pc.n_out) {
    vec4 total = red[0];
    vec4 coeff = lid == 0u ? pc.coeff0 : lid == 1u ? pc.coeff1 : lid == 2u ? pc.coeff2 : pc.coeff3;
    float v = dot(coeff, total) + pc.offset[lid];
    if ((pc.log_mask & (1u << lid)) != 0u) v = v > 0.0 ? -10.0 * log(v) / log(10.0) : uintBitsToFloat(0x7f800000u);
    values[pc.dst + gl_WorkGroupID.x * pc.n_out + lid] = v;
  }
}
