// Splat rasterizer: push constants, binding indices and sizes shared by engine/splat (C++) and
// shaders/splat (GLSL). See docs/rasterizer.md for what is computed.
#ifndef EVF_SPLAT_LAYOUT_H
#define EVF_SPLAT_LAYOUT_H
#include "common/shared_prelude.h"
#include "common/camera_layout.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kTileSize, 16u)
EVF_CONST(uint, kTilePixels, 256u)
EVF_CONST(uint, kProjectGroupSize, 128u)
EVF_CONST(uint, kIsectGroupSize, 256u)
EVF_CONST(uint, kFlagAntialiased, 1u)
EVF_CONST(uint, kFlagAccumulate, 2u)   // set when backward accumulates (the shader is the project_bwd_acc build)

struct ProjectPC {   // project, tile count, emit, project backward
  CameraPC cam;
  uint num_gaussians;
  uint sh_degree;    // active degree, <= the buffers' degree
  uint flags;
  uint tiles_x;
  uint tiles_y;
  uint depth_bits;   // sort key: tile << depth_bits | quantised depth
  uint num_isects;   // emit: slots available (offsets total)
  uint sentinel_key; // key of an unused slot: all sorted bits set, tile id past the last tile
};

struct RasterPC {    // tile ranges, rasterize, rasterize backward
  vec4 background;   // rgb, unused
  uint width;
  uint height;
  uint tiles_x;
  uint tiles_y;
  uint num_isects;
  uint depth_bits;
  uint subgroup_reduce;  // backward: 1 = subgroupAdd before the shared add (GPUs), 0 = per-lane adds
  uint pad1;
};

struct ReducePC {
  uint count;        // number of 6-vectors to sum
  uint pad0, pad1, pad2;
};

EVF_NAMESPACE_END
#endif
