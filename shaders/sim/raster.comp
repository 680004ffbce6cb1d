#version 450
// One workgroup = one 16x16 tile of one triangle's pixel range (work items are enumerated by the
// prefix sum of the per-triangle tile counts; small triangles have none: sim/raster_small). Each
// invocation tests kSimTileRows pixels of a column: CPU drivers pay per invocation of a workgroup
// that meets a barrier, and the triangle's edges are found once for them all.
#extension GL_GOOGLE_include_directive : require
#include "sim/sim_layout.h"
#include "common/dispatch.glsl"
#include "sim/raster_common.glsl"
layout(local_size_x = kSimTile, local_size_y = kSimTile / kSimTileRows) in;
#include "sim/raster_pixel.glsl"
layout(std430, binding = kSimRasterBindOffsets) readonly buffer Offsets { uint offsets[]; };  // n + 1 (exclusive scan)
shared uint s_tri;

void main() {
  uint item = evf_linear_group();
  uint n = pc.dims.z;
  if (gl_LocalInvocationIndex == 0u) {
    // Last triangle with offsets[tri] <= item (it has a non-zero count).
    uint lo = 0u, hi = n;  // invariant: offsets[lo] <= item < offsets[hi]
    while (hi - lo > 1u) {
      uint mid = (lo + hi) >> 1;
      if (offsets[mid] <= item) lo = mid; else hi = mid;
    }
    s_tri = lo;
  }
  barrier();
  uint tri = s_tri;
  if (item >= offsets[n]) return;
  uvec4 box = boxes[tri];
  uint tx0 = box.x / kSimTile, ntx = box.z / kSimTile - tx0 + 1u;
  uint local = item - offsets[tri];
  uint tx = tx0 + local % ntx, ty = box.y / kSimTile + local / ntx;
  uint x = tx * kSimTile + gl_LocalInvocationID.x;
  if (x < box.x || x > box.z) return;
  SimEdges t = sim_edges(cam[3u * tri].xyz, cam[3u * tri + 1u].xyz, cam[3u * tri + 2u].xyz);
  for (uint r = 0u; r < kSimTileRows; ++r) {
    uint y = ty * kSimTile + gl_LocalInvocationID.y + r * (kSimTile / kSimTileRows);
    if (y >= box.y && y <= box.w) sim_raster_pixel(tri, t, x, y);
  }
}
