#version 450
// Direct 3x3 convolution, stride 1, padding 1: the weight and bias gradients' partial sums
// (nn_layout.h, DirectGradPC), in the layout of nn/conv_bwd_weight (nn/conv_reduce adds them):
// for the blocks of split s, partial[s][co][ci * 9 + tap] = sum over the blocks' pixels p of
// dy[b][co][p] x[b][ci][p + tap offset], and partial[s][co][in_c * 9] = sum of dy[b][co][p].
// One invocation per (split, channel group, input channel): per block of 4 x kRows pixels
// it reads the kRows + 2 input rows and the kRows rows of dy of its kGroup
// output channels, then does 9 x 4 x kRows x kGroup multiply-adds from registers.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kDirectGroupSize) in;
#ifdef EVF_DIRECT_ANY_WIDTH
layout(std430, binding = kDirectDwBindX) readonly buffer X { float x[]; };
layout(std430, binding = kDirectDwBindDy) readonly buffer Dy { float dy[]; };
#else
layout(std430, binding = kDirectDwBindX) readonly buffer X { vec4 x[]; };
layout(std430, binding = kDirectDwBindDy) readonly buffer Dy { vec4 dy[]; };
#endif
layout(std430, binding = kDirectDwBindPartial) writeonly buffer Partial { float partial[]; };
layout(push_constant) uniform PC { DirectGradPC pc; };

#include "nn/direct_rows.glsl"

// The 4 values of dy's row oy, columns x0 .., of channel plane `plane` (0 outside the image).
vec4 load_dy(uint plane, uint oy, uint x0) {
  bool row_in = oy < pc.h;
  uint row = plane * pc.h + min(oy, pc.h - 1u);
#ifdef EVF_DIRECT_ANY_WIDTH
  vec4 v;
  [[unroll]] for (uint k = 0u; k < 4u; ++k)
    v[k] = row_in && x0 + k < pc.w ? dy[row * pc.w + min(x0 + k, pc.w - 1u)] : 0.0;
  return v;
#else
  return row_in ? dy[row * (pc.w / 4u) + x0 / 4u] : vec4(0.0);
#endif
}

void main() {
  uint i = evf_linear_invocation(kDirectGroupSize);
  if (i >= pc.splits * pc.groups * pc.in_c) return;
  uint ci = i % pc.in_c, g = (i / pc.in_c) % pc.groups, s = i / (pc.in_c * pc.groups);
  float acc[9][kGroup], acc_b[kGroup];
  [[unroll]] for (uint c = 0u; c < kGroup; ++c) {
    acc_b[c] = 0.0;
    [[unroll]] for (uint tap = 0u; tap < 9u; ++tap) acc[tap][c] = 0.0;
  }
  uint per_image = pc.blocks_x * pc.blocks_y;
  uint first = s * pc.blocks_per_split, last = min(first + pc.blocks_per_split, per_image * pc.images);
  for (uint blk = first; blk < last; ++blk) {
    uint b = blk / per_image, r = blk - b * per_image;
    uint x0 = (r % pc.blocks_x) * 4u, y0 = (r / pc.blocks_x) * kRows;
    vec4 rows[kRows + 2u][3];
    [[unroll]] for (uint k = 0u; k < kRows + 2u; ++k) load_row(b * pc.in_c + ci, int(y0 + k) - 1, x0, rows[k]);
    [[unroll]] for (uint c = 0u; c < kGroup; ++c) {
      uint co = min(g * kGroup + c, pc.out_c - 1u);  // channels past out_c: never stored
      [[unroll]] for (uint o = 0u; o < kRows; ++o) {
        vec4 d = load_dy(b * pc.out_c + co, y0 + o, x0);
        acc_b[c] += dot(d, vec4(1.0));
        [[unroll]] for (uint tap = 0u; tap < 9u; ++tap) acc[tap][c] += dot(d, rows[o + tap / 3u][tap % 3u]);
      }
    }
  }
  uint n = pc.in_c * 9u + 1u;
  [[unroll]] for (uint c = 0u; c < kGroup; ++c) {
    uint co = g * kGroup + c;
    if (co >= pc.out_c) break;
    uint base = (s * pc.out_c + co) * n;
    [[unroll]] for (uint tap = 0u; tap < 9u; ++tap) partial[base + ci * 9u + tap] = acc[tap][c];
    if (ci == 0u) partial[base + n - 1u] = acc_b[c];
  }
}
