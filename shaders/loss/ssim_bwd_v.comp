#version 450
// SSIM backward, vertical pass: finishes E[d1], E[d3], E[d5] and writes
//   grad (+)= ssim_grad_scale * (E[d1] + 2 A E[d3] + B E[d5]) + pixel_grad_scale * de/dA
// where e is the per-pixel term (|A-B|: sign(A-B); (A-B)^2: 2(A-B)). One invocation: a column
// strip of kSsimStrip pixels, as in ssim_v.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/texel.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(binding = kSsimBwdVBindA) uniform samplerBuffer A;
layout(binding = kSsimBwdVBindB) uniform samplerBuffer B;
layout(binding = kSsimBwdVBindH) uniform samplerBuffer H;  // see loss_layout.h
// What an accumulating pass adds to is read through a texel view of the same buffer (each element
// read, then written, by its own invocation alone; docs/gpu.md).
layout(std430, binding = kSsimBwdVBindGrad) writeonly buffer Grad { float grad[]; };
layout(binding = kSsimBwdVBindGradIn) uniform samplerBuffer GradIn;
layout(push_constant) uniform PC { SsimPC pc; };

const int kRows = int(kSsimStrip);
const int kSpan = kRows + 2 * kSsimRadius;

void main() {
  uint j = evf_linear_invocation(kLossGroupSize);
  uint strips = (pc.height + kSsimStrip - 1u) / kSsimStrip;
  if (j >= pc.channels * strips * pc.width) return;
  uint x = j % pc.width;
  uint t = j / pc.width;
  uint strip = t % strips;
  uint c = t / strips;
  int y0 = int(strip * kSsimStrip);
  int h = int(pc.height);
  uint col = c * pc.height * pc.width + x;
  vec3 acc[kRows];
  [[unroll]] for (int o = 0; o < kRows; ++o) acc[o] = vec3(0.0);
  [[unroll]] for (int r = 0; r < kSpan; ++r) {
    int yy = y0 - kSsimRadius + r;
    if (yy < 0 || yy >= h) continue;
    vec3 hv = texelFetch(H, int(col + uint(yy) * pc.width)).xyz;
    [[unroll]] for (int o = 0; o < kRows; ++o) {
      int k = r - o;
      if (k >= 0 && k <= 2 * kSsimRadius) acc[o] += kSsimG[k] * hv;
    }
  }
  [[unroll]] for (int o = 0; o < kRows; ++o) {
    if (y0 + o >= h) break;
    uint i = col + uint(y0 + o) * pc.width;
    float a = evf_texel_float(A, i), b = evf_texel_float(B, i);
    float d_ssim = acc[o].x + 2.0 * a * acc[o].y + b * acc[o].z;
    float diff = a - b;
    float d_pix = (pc.flags & kLossPixelL2) != 0u ? 2.0 * diff : sign(diff);
    float g = pc.ssim_grad_scale * d_ssim + pc.pixel_grad_scale * d_pix;
    if ((pc.flags & kLossAccumulate) != 0u) g += evf_texel_float(GradIn, i);
    grad[i] = g;
  }
}
