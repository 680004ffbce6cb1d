#version 450
// SSIM backward, vertical pass: finishes E[d1], E[d3], E[d5] and writes
//   grad (+)= ssim_grad_scale * (E[d1] + 2 A E[d3] + B E[d5]) + pixel_grad_scale * de/dA
// where e is the per-pixel term (|A-B|: sign(A-B); (A-B)^2: 2(A-B)).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "loss/ssim_math.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer A { float img_a[]; };
layout(std430, binding = 1) readonly buffer B { float img_b[]; };
layout(std430, binding = 2) readonly buffer H { float hmap[]; };
layout(std430, binding = 3) buffer Grad { float grad[]; };
layout(push_constant) uniform PC { SsimPC pc; };

void main() {
  uint i = evf_linear_invocation(kLossGroupSize);
  if (i >= pc.count) return;
  uint plane = pc.height * pc.width;
  uint c = i / plane;
  int y = int((i - c * plane) / pc.width);
  int h = int(pc.height);
  vec3 acc = vec3(0.0);
  for (int k = -kSsimRadius; k <= kSsimRadius; ++k) {
    int yy = y + k;
    if (yy < 0 || yy >= h) continue;
    uint j = uint(int(i) + k * int(pc.width));
    acc += kSsimG[k + kSsimRadius] * vec3(hmap[j], hmap[pc.count + j], hmap[2u * pc.count + j]);
  }
  float a = img_a[i], b = img_b[i];
  float d_ssim = acc.x + 2.0 * a * acc.y + b * acc.z;
  float diff = a - b;
  float d_pix = (pc.flags & kLossPixelL2) != 0u ? 2.0 * diff : sign(diff);
  float g = pc.ssim_grad_scale * d_ssim + pc.pixel_grad_scale * d_pix;
  if ((pc.flags & kLossAccumulate) != 0u) g += grad[i];
  grad[i] = g;
}
