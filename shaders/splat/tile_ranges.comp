#version 450
// Per-tile ranges of the sorted intersection list: one invocation per intersection marks where
// its tile's run begins and ends. tile_range must be zeroed first (empty tiles stay [0, 0)).
#extension GL_GOOGLE_include_directive : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kIsectGroupSize) in;
layout(std430, binding = kTileRangesBindKeys) readonly buffer Keys { uint keys[]; };
layout(std430, binding = kTileRangesBindRanges) buffer Ranges { uvec2 tile_range[]; };
layout(push_constant) uniform PC { RasterPC pc; };
void main() {
  uint i = evf_linear_invocation(kIsectGroupSize);
  if (i >= pc.num_isects) return;
  uint num_tiles = pc.tiles_x * pc.tiles_y;
  uint tile = keys[i] >> pc.depth_bits;
  if (tile >= num_tiles) return;
  if (i == 0 || (keys[i - 1] >> pc.depth_bits) != tile) tile_range[tile].x = i;
  if (i + 1 == pc.num_isects || (keys[i + 1] >> pc.depth_bits) != tile) tile_range[tile].y = i + 1;
}
