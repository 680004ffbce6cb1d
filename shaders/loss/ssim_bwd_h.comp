#version 450
// SSIM backward, horizontal pass: the same 11-tap filter (its own adjoint) applied along x to
// the per-pixel partials d1, d3, d5 (planes 0..2 of D), into planes 0..2 of H.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer D { float dmap[]; };
layout(std430, binding = 1) writeonly buffer H { float hmap[]; };
layout(push_constant) uniform PC { SsimPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  if (i >= pc.count) return;
  int x = int(i % pc.width);
  uint row = i - uint(x);
  int w = int(pc.width);
  vec3 acc = vec3(0.0);
  for (int k = -kSsimRadius; k <= kSsimRadius; ++k) {
    int xx = x + k;
    if (xx < 0 || xx >= w) continue;
    uint j = row + uint(xx);
    acc += kSsimG[k + kSsimRadius] * vec3(dmap[j], dmap[pc.count + j], dmap[2u * pc.count + j]);
  }
  hmap[i] = acc.x;
  hmap[pc.count + i] = acc.y;
  hmap[2u * pc.count + i] = acc.z;
}
