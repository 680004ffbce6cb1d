#version 450
// One invocation = one small triangle (sim_small_box): it tests every pixel of its box itself.
// A 16x16 workgroup per tile would leave most of its invocations idle on such a triangle.
#extension GL_GOOGLE_include_directive : require
#include "sim/sim_layout.h"
#include "common/dispatch.glsl"
#include "sim/raster_common.glsl"
layout(local_size_x = kSimSmallGroupSize) in;
#include "sim/raster_pixel.glsl"

void main() {
  uint tri = evf_linear_invocation(kSimSmallGroupSize);
  if (tri >= pc.dims.z) return;
  uvec4 box = boxes[tri];
  if (!sim_small_box(box, pc.misc.z)) return;
  // The vertices are read once: inside the loop each read would be one per pixel.
  SimEdges t = sim_edges(cam[3u * tri].xyz, cam[3u * tri + 1u].xyz, cam[3u * tri + 2u].xyz);
  for (uint y = box.y; y <= box.w; ++y)
    for (uint x = box.x; x <= box.z; ++x) sim_raster_pixel(tri, t, x, y);
}
