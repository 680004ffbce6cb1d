#version 450
// SSIM backward, horizontal pass: the same 11-tap filter (its own adjoint) applied along x to
// the per-pixel partials d1, d3, d5 (D[i].xyz), into H[i].xyz. One invocation:
// a row segment of kSsimStrip pixels, as in ssim_h.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(binding = kSsimBwdHBindD) uniform samplerBuffer D;  // see loss_layout.h
layout(std430, binding = kSsimBwdHBindH) writeonly buffer H { vec4 hmap[]; };
layout(push_constant) uniform PC { SsimPC pc; };

const int kCols = int(kSsimStrip);
const int kSpan = kCols + 2 * kSsimRadius;

void main() {
  uint j = evf_linear_invocation(kLossGroupSize);
  uint segs = (pc.width + kSsimStrip - 1u) / kSsimStrip;
  if (j >= pc.channels * pc.height * segs) return;
  uint seg = j % segs;
  uint row = (j / segs) * pc.width;
  int x0 = int(seg * kSsimStrip);
  int w = int(pc.width);
  vec3 acc[kCols];
  [[unroll]] for (int o = 0; o < kCols; ++o) acc[o] = vec3(0.0);
  [[unroll]] for (int r = 0; r < kSpan; ++r) {
    int xx = x0 - kSsimRadius + r;
    if (xx < 0 || xx >= w) continue;
    vec3 v = texelFetch(D, int(row + uint(xx))).xyz;
    [[unroll]] for (int o = 0; o < kCols; ++o) {
      int k = r - o;
      if (k >= 0 && k <= 2 * kSsimRadius) acc[o] += kSsimG[k] * v;
    }
  }
  [[unroll]] for (int o = 0; o < kCols; ++o) {
    if (x0 + o >= w) break;
    uint i = row + uint(x0 + o);
    hmap[i] = vec4(acc[o], 0.0);
  }
}
