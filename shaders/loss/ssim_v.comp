#version 450
// SSIM forward, vertical pass: finishes the four windowed moments, evaluates SSIM per pixel,
// stores its partial derivatives for the backward (kLossWriteGrad) and the map
// (kLossWriteSsimMap), and sums (pixel term, SSIM) per workgroup. One invocation: a column strip
// of kSsimStrip pixels (channel c, rows [y0, y0 + kSsimStrip), column x).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/texel.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(binding = kSsimVBindA) uniform samplerBuffer A;
layout(binding = kSsimVBindB) uniform samplerBuffer B;
layout(binding = kSsimVBindH) uniform samplerBuffer H;  // see loss_layout.h
layout(std430, binding = kSsimVBindD) writeonly buffer D { vec4 dmap[]; };
layout(std430, binding = kSsimVBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { SsimPC pc; };

const int kRows = int(kSsimStrip);
const int kSpan = kRows + 2 * kSsimRadius;

void main() {
  uint j = evf_linear_invocation(kLossGroupSize);
  uint strips = (pc.height + kSsimStrip - 1u) / kSsimStrip;
  vec4 contrib = vec4(0.0);
  if (j < pc.channels * strips * pc.width) {
    uint x = j % pc.width;
    uint t = j / pc.width;
    uint strip = t % strips;
    uint c = t / strips;
    int y0 = int(strip * kSsimStrip);
    int h = int(pc.height);
    uint col = c * pc.height * pc.width + x;
    vec4 m[kRows];
    [[unroll]] for (int o = 0; o < kRows; ++o) m[o] = vec4(0.0);
    // Rows in increasing order: each output receives its taps in the order k = 0..10.
    [[unroll]] for (int r = 0; r < kSpan; ++r) {
      int yy = y0 - kSsimRadius + r;
      if (yy < 0 || yy >= h) continue;
      vec4 hv = texelFetch(H, int(col + uint(yy) * pc.width));
      [[unroll]] for (int o = 0; o < kRows; ++o) {
        int k = r - o;
        if (k >= 0 && k <= 2 * kSsimRadius) m[o] += kSsimG[k] * hv;
      }
    }
    [[unroll]] for (int o = 0; o < kRows; ++o) {
      if (y0 + o >= h) break;
      uint i = col + uint(y0 + o) * pc.width;
      SsimPixel s = ssim_eval(m[o], pc.c1, pc.c2);
      float diff = evf_texel_float(A, i) - evf_texel_float(B, i);
      float e = (pc.flags & kLossPixelL2) != 0u ? diff * diff : abs(diff);
      contrib += vec4(e, s.ssim, 0.0, 0.0);
      if ((pc.flags & kLossWriteGrad) != 0u) {
        dmap[i] = vec4(s.d1, s.d3, s.d5, 0.0);
      }
      if ((pc.flags & kLossWriteSsimMap) != 0u) dmap[pc.count + (i >> 2u)][i & 3u] = s.ssim;
    }
  }
  vec4 total = loss_group_sum(contrib);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
