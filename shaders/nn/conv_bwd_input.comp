#version 450
// Convolution backward to the input (nn_layout.h): dx[ci][i] = sum over (co, tap) of
// W[co][ci][tap] dy[co][the output pixel whose tap reads i], as the tiled implicit GEMM; written,
// or added with pc.accumulate.
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(std430, binding = kConvBwdInputBindDy) readonly buffer Dy { float dy[]; };
layout(std430, binding = kConvBwdInputBindW) readonly buffer Weight { float w[]; };
layout(std430, binding = kConvBwdInputBindDx) buffer Dx { float dx[]; };
layout(push_constant) uniform PC { ConvPC pc; };
#include "nn/conv_math.glsl"

vec4 gemm_load_a(uint m, uint k) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  uint taps = pc.ksize * pc.ksize, co = k / taps, t = k - co * taps;
  for (uint j = 0u; j < 4u; ++j)
    if (m + j < pc.gemm_m) v[j] = w[(co * pc.in_c + m + j) * taps + t];
  return v;
}

vec4 gemm_load_b(uint k, uint n) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  ConvTap t = conv_tap(k);
  uvec2 i = conv_pixel(n, pc.in_w), o;
  for (uint j = 0u; j < 4u; ++j) {
    if (n + j < pc.gemm_n && conv_output_of(ivec2(i), t, o)) v[j] = dy[(t.c * pc.out_h + o.y) * pc.out_w + o.x];
    i = conv_pixel_next(i, pc.in_w);
  }
  return v;
}

void gemm_store(uint m, uint n, float c) {
  uint e = m * pc.gemm_n + n;
  dx[e] = pc.accumulate != 0u ? dx[e] + c : c;
}

#include "nn/gemm.glsl"

void main() {
  uint m0, n0;
  if (!gemm_tile_origin(m0, n0)) return;
  gemm_tile(m0, n0, 0u, pc.gemm_k);
}
