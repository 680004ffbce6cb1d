#version 450
// SSIM forward, vertical pass: finishes the five windowed moments, evaluates SSIM per pixel,
// stores its partial derivatives for the backward (kLossWriteGrad) and the map
// (kLossWriteSsimMap), and sums (pixel term, SSIM) per workgroup.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer A { float img_a[]; };
layout(std430, binding = 1) readonly buffer B { float img_b[]; };
layout(std430, binding = 2) readonly buffer H { float hmap[]; };
layout(std430, binding = 3) writeonly buffer D { float dmap[]; };
layout(std430, binding = 4) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { SsimPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  vec4 contrib = vec4(0.0);
  if (i < pc.count) {
    uint plane = pc.height * pc.width;
    uint c = i / plane;
    uint rem = i - c * plane;
    int y = int(rem / pc.width);
    int h = int(pc.height);
    vec4 m = vec4(0.0);
    float mab = 0.0;
    for (int k = -kSsimRadius; k <= kSsimRadius; ++k) {
      int yy = y + k;
      if (yy < 0 || yy >= h) continue;
      float g = kSsimG[k + kSsimRadius];
      uint j = uint(int(i) + k * int(pc.width));
      m += g * vec4(hmap[j], hmap[pc.count + j], hmap[2u * pc.count + j], hmap[3u * pc.count + j]);
      mab += g * hmap[4u * pc.count + j];
    }
    SsimPixel s = ssim_eval(m, mab, pc.c1, pc.c2);
    float diff = img_a[i] - img_b[i];
    float e = (pc.flags & kLossPixelL2) != 0u ? diff * diff : abs(diff);
    contrib = vec4(e, s.ssim, 0.0, 0.0);
    if ((pc.flags & kLossWriteGrad) != 0u) {
      dmap[i] = s.d1;
      dmap[pc.count + i] = s.d3;
      dmap[2u * pc.count + i] = s.d5;
    }
    if ((pc.flags & kLossWriteSsimMap) != 0u) dmap[3u * pc.count + i] = s.ssim;
  }
  vec4 total = loss_group_sum(contrib);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
