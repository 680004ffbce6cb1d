#version 450
// Convolution backward to the weights and bias, second pass (nn_layout.h): each weight (and bias)
// gradient is the sum of its pc.splits partial sums, added in split order; written into dw / db,
// or added to them with pc.accumulate. gemm_m = output channels, gemm_n = weights per output
// channel + 1 (the bias column).
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kReduceGroupSize) in;
layout(std430, binding = kConvReduceBindPartial) readonly buffer Partial { float partial[]; };
layout(std430, binding = kConvReduceBindDw) buffer Dw { float dw[]; };
layout(std430, binding = kConvReduceBindDb) buffer Db { float db[]; };
layout(push_constant) uniform PC { ConvPC pc; };

void main() {
  uint e = evf_linear_invocation(kReduceGroupSize), per_split = pc.gemm_m * pc.gemm_n;
  if (e >= per_split) return;
  float sum = 0.0;
  for (uint s = 0u; s < pc.splits; ++s) sum += partial[s * per_split + e];
  uint m = e / pc.gemm_n, n = e - m * pc.gemm_n, weights = pc.gemm_n - 1u;
  if (n < weights) {
    uint i = m * weights + n;
    dw[i] = pc.accumulate != 0u ? dw[i] + sum : sum;
  } else {
    db[m] = pc.accumulate != 0u ? db[m] + sum : sum;
  }
}
