#version 450
// x2 nearest up-sampling backward (nn_layout.h, PointwisePC): one invocation per low-resolution
// value (pc.count of them), the sum of the up to four output gradients it was copied to, in a fixed
// order; written, or added with pc.accumulate.
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kNnGroupSize) in;
layout(std430, binding = kActBwdBindDy) readonly buffer Dy { float dy[]; };
layout(std430, binding = kActBwdBindDx) buffer Dx { float dx[]; };
layout(push_constant) uniform PC { PointwisePC pc; };

void main() {
  uint i = evf_linear_invocation(kNnGroupSize);
  if (i >= pc.count) return;
  uint in_hw = pc.in_h * pc.in_w, c = i / in_hw, p = i - c * in_hw, y = p / pc.in_w, x = p - y * pc.in_w;
  float g = 0.0;
  for (uint sy = 2u * y; sy < min(2u * y + 2u, pc.out_h); ++sy)
    for (uint sx = 2u * x; sx < min(2u * x + 2u, pc.out_w); ++sx) g += dy[(c * pc.out_h + sy) * pc.out_w + sx];
  dx[i] = pc.accumulate != 0u ? dx[i] + g : g;
}
