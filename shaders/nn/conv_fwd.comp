#version 450
// Convolution forward (nn_layout.h): y[b][co][p] = bias[co] + sum over (ci, tap) of
// W[co][ci][tap] x[b][ci][tap's input pixel of p], as the tiled implicit GEMM.
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(std430, binding = kConvFwdBindX) readonly buffer X { float x[]; };
layout(std430, binding = kConvFwdBindW) readonly buffer Weight { float w[]; };
layout(std430, binding = kConvFwdBindBias) readonly buffer Bias { float bias[]; };
layout(std430, binding = kConvFwdBindY) writeonly buffer Y { float y[]; };
layout(push_constant) uniform PC { ConvPC pc; };
#include "nn/conv_math.glsl"

vec4 gemm_load_a(uint m, uint k) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  for (uint j = 0u; j < 4u; ++j)
    if (m + j < pc.gemm_m) v[j] = w[(m + j) * pc.gemm_k + k];
  return v;
}

vec4 gemm_load_b(uint k, uint n) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  ConvTap t = conv_tap(k);
  uvec3 o = conv_pixel(n, pc.out_w, pc.out_h);
  for (uint j = 0u; j < 4u; ++j) {
    ivec2 i = conv_input_pixel(o.xy, t);
    if (n + j < pc.gemm_n && conv_inside_input(i)) v[j] = x[conv_element(t.c, uvec2(i), o.z, pc.in_c, pc.in_h, pc.in_w)];
    o = conv_pixel_next(o, pc.out_w, pc.out_h);
  }
  return v;
}

void gemm_store(uint m, uint n, float c) { y[conv_plane_element(m, n, pc.out_c, pc.out_h * pc.out_w)] = c + bias[m]; }

#include "nn/gemm.glsl"

void main() {
  uint m0, n0;
  if (!gemm_tile_origin(m0, n0)) return;
  gemm_tile(m0, n0, 0u, pc.gemm_k);
}
