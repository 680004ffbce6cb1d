#version 450
// The chain from per-pixel flow gradients to the node grid, tile by tile: one workgroup per
// (tile, interval) sums, over the pixels of the tile (the cell flow_cell assigns them to), each
// pixel's gradient times its bilinear weight of the tile's four corner nodes. Each pixel is read
// once; the host adds each node's (up to four) tile sums in a fixed order. Workgroup sums by
// common/group_sum.glsl: reproducible.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
#define EVF_GROUP_SUM_SIZE kFlowGroupSize
#include "common/group_sum.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowReduceBindGradField) readonly buffer GradField { vec2 grad_field[]; };
layout(std430, binding = kFlowReduceBindTileGrad) writeonly buffer TileGrad { vec2 tile_grad[]; };
layout(push_constant) uniform PC { FlowNodeReducePC pc; };
vec2 flow_node(uint i) { return vec2(0.0); }
#include "flow/flow_math.glsl"

// Pixels whose centre flow_cell puts in cell a of n along an axis of `size` pixels: [first, last)
// (a one-pixel margin each side, checked per pixel).
uvec2 axis_cell(uint size, uint a) {
  int lo = int(floor(float(a) * float(size) / float(pc.tiles))) - 1;
  int hi = int(ceil(float(a + 1u) * float(size) / float(pc.tiles))) + 1;
  return uvec2(clamp(lo, 0, int(size)), clamp(hi, 0, int(size)));
}

void main() {
  const uint cells = pc.tiles * pc.tiles;
  const uint group = evf_linear_group();
  const uint p = group / cells, cell = group % cells;  // p: the interval
  const uint a = cell % pc.tiles, b = cell / pc.tiles;
  const uvec2 xs = axis_cell(pc.width, a), ys = axis_cell(pc.height, b);
  const uint w = xs.y - xs.x, count = w * (ys.y - ys.x);
  vec2 g00 = vec2(0.0), g10 = vec2(0.0), g01 = vec2(0.0), g11 = vec2(0.0);
  if (p < pc.intervals) {
    for (uint i = gl_LocalInvocationIndex; i < count; i += kFlowGroupSize) {
      const uint x = xs.x + i % w, y = ys.x + i / w;
      uint ca, cb;
      float fa, fb;
      flow_cell(float(x) + 0.5, pc.width, pc.tiles, ca, fa);
      flow_cell(float(y) + 0.5, pc.height, pc.tiles, cb, fb);
      if (ca != a || cb != b) continue;
      const vec2 g = grad_field[(p * pc.height + y) * pc.width + x];
      g00 += (1.0 - fa) * (1.0 - fb) * g;
      g10 += fa * (1.0 - fb) * g;
      g01 += (1.0 - fa) * fb * g;
      g11 += fa * fb * g;
    }
  }
  const vec2 s00 = evf_group_sum(g00);
  barrier();
  const vec2 s10 = evf_group_sum(g10);
  barrier();
  const vec2 s01 = evf_group_sum(g01);
  barrier();
  const vec2 s11 = evf_group_sum(g11);
  if (gl_LocalInvocationIndex == 0u && p < pc.intervals) {
    const uint o = (p * cells + cell) * 4u;
    tile_grad[o] = s00;
    tile_grad[o + 1u] = s10;
    tile_grad[o + 2u] = s01;
    tile_grad[o + 3u] = s11;
  }
}
