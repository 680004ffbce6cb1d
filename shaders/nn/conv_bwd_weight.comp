#version 450
// Convolution backward to the weights and bias, first pass (nn_layout.h): for the output pixels
// of split s (gl_WorkGroupID.z), partial[s][co][(ci, tap)] = sum over pixels (b, p) of
// dy[b][co][p] x[b][ci][tap's input pixel of p], and in the last column (the bias) sum of dy[b][co][p].
#extension GL_GOOGLE_include_directive : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(std430, binding = kConvBwdWeightBindX) readonly buffer X { float x[]; };
layout(std430, binding = kConvBwdWeightBindDy) readonly buffer Dy { float dy[]; };
layout(std430, binding = kConvBwdWeightBindPartial) writeonly buffer Partial { float partial[]; };
layout(push_constant) uniform PC { ConvPC pc; };
#include "nn/conv_math.glsl"

vec4 gemm_load_a(uint m, uint k) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  uint hw = pc.out_h * pc.out_w, e = conv_plane_element(m, k, pc.out_c, hw);
  for (uint j = 0u; j < 4u; ++j)
    if (m + j < pc.gemm_m) v[j] = dy[e + j * hw];
  return v;
}

vec4 gemm_load_b(uint k, uint n) {
  vec4 v = vec4(0.0);
  if (k >= pc.gemm_k) return v;
  uvec3 o = conv_pixel(k, pc.out_w, pc.out_h);
  uint bias_column = pc.gemm_n - 1u;
  ConvTap t = conv_tap(min(n, bias_column));
  for (uint j = 0u; j < 4u; ++j) {
    ivec2 i = conv_input_pixel(o.xy, t);
    if (n + j == bias_column) v[j] = 1.0;
    else if (n + j < bias_column && conv_inside_input(i)) v[j] = x[conv_element(t.c, uvec2(i), o.z, pc.in_c, pc.in_h, pc.in_w)];
    t = conv_tap_next(t);
  }
  return v;
}

void gemm_store(uint m, uint n, float c) { partial[(gl_WorkGroupID.z * pc.gemm_m + m) * pc.gemm_n + n] = c; }

#include "nn/gemm.glsl"

void main() {
  uint m0, n0;
  if (!gemm_tile_origin(m0, n0)) return;
  uint k_begin = gl_WorkGroupID.z * pc.pixels_per_split;
  gemm_tile(m0, n0, k_begin, min(k_begin + pc.pixels_per_split, pc.gemm_k));
}
