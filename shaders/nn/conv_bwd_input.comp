#version 450
// Convolution backward to the input (nn_layout.h): dx[b][ci][i] = sum over (co, tap) of
// W[co][ci][tap] dy[b][co][the output pixel whose tap reads i], as the tiled implicit GEMM; written,
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
  uvec3 i = conv_pixel(n, pc.in_w, pc.in_h);
  uvec2 o;
  for (uint j = 0u; j < 4u; ++j) {
    if (n + j < pc.gemm_n && conv_output_of(ivec2(i.xy), t, o)) v[j] = dy[conv_element(t.c, o, i.z, pc.out_c, pc.out_h, pc.out_w)];
    i = conv_pixel_next(i, pc.in_w, pc.in_h);
  }
  return v;
}

void gemm_store(uint m, uint n, float c) {
  uint e = conv_plane_element(m, n, pc.in_c, pc.in_h * pc.in_w);
  dx[e] = pc.accumulate != 0u ? dx[e] + c : c;
}

#include "nn/gemm.glsl"

void main() {
  uint m0, n0;
  if (!gemm_tile_origin(m0, n0)) return;
  gemm_tile(m0, n0, 0u, pc.gemm_k);
}
