#version 450
// The direct convolution's weights (nn_layout.h, WeightTPC): WT[r][tap][c] from W[co][ci][tap],
// one invocation per WT value, zero where c lies in the padding. Forward: r = ci, c = co.
// Input gradient (flip): r = co, c = ci, and the tap mirrored (8 - tap).
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kNnGroupSize) in;
layout(std430, binding = kWeightTBindW) readonly buffer Weight { float w[]; };
layout(std430, binding = kWeightTBindWT) writeonly buffer WeightT { float wt[]; };
layout(push_constant) uniform PC { WeightTPC pc; };

void main() {
  uint i = evf_linear_invocation(kNnGroupSize);
  if (i >= pc.rows * 9u * pc.cols) return;
  uint c = i % pc.cols, tap = (i / pc.cols) % 9u, r = i / (9u * pc.cols);
  uint c_count = pc.flip != 0u ? pc.in_c : pc.out_c;
  uint cc = min(c, c_count - 1u);  // an index inside W for the padding too (its value is not used)
  uint co = pc.flip != 0u ? r : cc, ci = pc.flip != 0u ? cc : r;
  uint t = pc.flip != 0u ? 8u - tap : tap;
  wt[i] = c < c_count ? w[(co * pc.in_c + ci) * 9u + t] : 0.0;
}
