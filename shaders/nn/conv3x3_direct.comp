#version 450
// Direct 3x3 convolution, stride 1, padding 1 (nn_layout.h, DirectConvPC): y[b][co][p] =
// bias[co] + sum over (ci, tap) of WT[ci][tap][co] x[b][ci][p + tap offset] (0 outside the image),
// written or added. One invocation per block of 4 x kRows pixels and kGroup output
// channels; see nn_layout.h for why and for WT.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "nn/nn_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kDirectGroupSize) in;
// EVF_DIRECT_ANY_WIDTH (nn/conv3x3_direct_any): images of any width, read and written one value
// at a time; else rows of whole vec4s (w % 4 == 0), three reads and one write per row of a block.
#ifdef EVF_DIRECT_ANY_WIDTH
layout(std430, binding = kDirectBindX) readonly buffer X { float x[]; };
layout(std430, binding = kDirectBindY) buffer Y { float y[]; };
#else
layout(std430, binding = kDirectBindX) readonly buffer X { vec4 x[]; };
layout(std430, binding = kDirectBindY) buffer Y { vec4 y[]; };
#endif
layout(std430, binding = kDirectBindWT) readonly buffer WeightT { vec4 wt[]; };  // [ci][tap][out_pad / 4]
layout(std430, binding = kDirectBindBias) readonly buffer Bias { float bias[]; };
layout(push_constant) uniform PC { DirectConvPC pc; };

#include "nn/direct_rows.glsl"
const uint kQuads = kGroup / 4u;

#ifdef EVF_DIRECT_ANY_WIDTH
// Adds or writes the 4 values of output row oy, columns x0 .., of channel plane `plane`.
void store_row(uint plane, uint oy, uint x0, vec4 v) {
  uint row = (plane * pc.h + oy) * pc.w;
  [[unroll]] for (uint k = 0u; k < 4u; ++k) {
    if (x0 + k >= pc.w) break;
    y[row + x0 + k] = pc.accumulate != 0u ? y[row + x0 + k] + v[k] : v[k];
  }
}
#else
void store_row(uint plane, uint oy, uint x0, vec4 v) {
  uint q = (plane * pc.h + oy) * (pc.w / 4u) + x0 / 4u;
  y[q] = pc.accumulate != 0u ? y[q] + v : v;
}
#endif

void main() {
  uint i = evf_linear_invocation(kDirectGroupSize);
  uint per_image = pc.blocks_x * pc.blocks_y * pc.groups;
  if (i >= per_image * pc.images) return;
  uint b = i / per_image, r = i - b * per_image;
  uint g = r / (pc.blocks_x * pc.blocks_y), blk = r - g * (pc.blocks_x * pc.blocks_y);
  uint x0 = (blk % pc.blocks_x) * 4u, y0 = (blk / pc.blocks_x) * kRows;
  vec4 acc[kRows][kGroup];  // [output row][channel of the group], 4 pixels each
  [[unroll]] for (uint o = 0u; o < kRows; ++o)
    [[unroll]] for (uint c = 0u; c < kGroup; ++c) acc[o][c] = vec4(0.0);
  uint wq = pc.out_pad / 4u;
  for (uint ci = 0u; ci < pc.in_c; ++ci) {
    vec4 rows[kRows + 2u][3];
    [[unroll]] for (uint k = 0u; k < kRows + 2u; ++k) load_row(b * pc.in_c + ci, int(y0 + k) - 1, x0, rows[k]);
    [[unroll]] for (uint tap = 0u; tap < 9u; ++tap) {
      uint ky = tap / 3u, kx = tap % 3u;
      vec4 wv[kQuads];
      [[unroll]] for (uint q = 0u; q < kQuads; ++q) wv[q] = wt[(ci * 9u + tap) * wq + g * kQuads + q];
      [[unroll]] for (uint o = 0u; o < kRows; ++o)
        [[unroll]] for (uint c = 0u; c < kGroup; ++c)
          acc[o][c] = fma(vec4(wv[c / 4u][c % 4u]), rows[o + ky][kx], acc[o][c]);
    }
  }
  [[unroll]] for (uint c = 0u; c < kGroup; ++c) {
    uint co = g * kGroup + c;
    if (co >= pc.out_c) break;
    float add = pc.bias != 0u ? bias[pc.bias != 0u ? co : 0u] : 0.0;  // index in range either way
    [[unroll]] for (uint o = 0u; o < kRows; ++o) {
      if (y0 + o >= pc.h) break;
      store_row(b * pc.out_c + co, y0 + o, x0, acc[o][c] + add);
    }
  }
}
