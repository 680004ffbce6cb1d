#version 450
// SSIM forward, horizontal pass: the 11-tap filter of A, B, A^2 + B^2, AB along x (zero padding).
// One invocation: a row segment of kSsimStrip pixels (channel c, row y, x in [x0, x0 + strip)).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/texel.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(binding = kSsimHBindA) uniform samplerBuffer A;
layout(binding = kSsimHBindB) uniform samplerBuffer B;
layout(std430, binding = kSsimHBindH) writeonly buffer H { vec4 hmap[]; };  // see loss_layout.h
layout(push_constant) uniform PC { SsimPC pc; };

const int kCols = int(kSsimStrip);
const int kSpan = kCols + 2 * kSsimRadius;

void main() {
  uint j = evf_linear_invocation(kLossGroupSize);
  uint segs = (pc.width + kSsimStrip - 1u) / kSsimStrip;
  if (j >= pc.channels * pc.height * segs) return;
  uint seg = j % segs;
  uint row = (j / segs) * pc.width;  // c*H*W + y*W
  int x0 = int(seg * kSsimStrip);
  int w = int(pc.width);
  vec4 m[kCols];
  [[unroll]] for (int o = 0; o < kCols; ++o) m[o] = vec4(0.0);
  // Columns in increasing order: each output receives its taps in the order k = 0..10.
  [[unroll]] for (int r = 0; r < kSpan; ++r) {
    int xx = x0 - kSsimRadius + r;
    if (xx < 0 || xx >= w) continue;
    float a = evf_texel_float(A, row + uint(xx)), b = evf_texel_float(B, row + uint(xx));
    vec4 v = vec4(a, b, a * a + b * b, a * b);
    [[unroll]] for (int o = 0; o < kCols; ++o) {
      int k = r - o;
      if (k >= 0 && k <= 2 * kSsimRadius) m[o] += kSsimG[k] * v;
    }
  }
  [[unroll]] for (int o = 0; o < kCols; ++o) {
    if (x0 + o >= w) break;
    hmap[row + uint(x0 + o)] = m[o];
  }
}
