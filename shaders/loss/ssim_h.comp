#version 450
// SSIM forward, horizontal pass: the 11-tap filter of A, B, A^2, B^2, AB along x (zero padding).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer A { float img_a[]; };
layout(std430, binding = 1) readonly buffer B { float img_b[]; };
layout(std430, binding = 2) writeonly buffer H { float hmap[]; };
layout(push_constant) uniform PC { SsimPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  if (i >= pc.count) return;
  int x = int(i % pc.width);
  uint row = i - uint(x);
  int w = int(pc.width);
  vec4 m = vec4(0.0);
  float mab = 0.0;
  for (int k = -kSsimRadius; k <= kSsimRadius; ++k) {
    int xx = x + k;
    if (xx < 0 || xx >= w) continue;
    float g = kSsimG[k + kSsimRadius];
    float a = img_a[row + uint(xx)], b = img_b[row + uint(xx)];
    m += g * vec4(a, b, a * a, b * b);
    mab += g * (a * b);
  }
  hmap[i] = m.x;
  hmap[pc.count + i] = m.y;
  hmap[2u * pc.count + i] = m.z;
  hmap[3u * pc.count + i] = m.w;
  hmap[4u * pc.count + i] = mab;
}
