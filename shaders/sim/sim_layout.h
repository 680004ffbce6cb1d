// Mesh renderer of the simulator (engine/sim): layouts shared by engine/sim and shaders/sim.
//
// Triangles are rendered by ray casting through pixel centres: a pixel (x, y) is covered when the
// ray through (x + 0.5, y + 0.5) meets the triangle (watertight: shared edges use the same scalar
// triple products with opposite signs). Passes: tri_setup (camera-space vertices, clipped screen
// bounding box in 16x16 tiles, tile count; none for a small triangle) -> prefix sum of the counts ->
// raster_small and raster (mode 0: atomicMin of the depth bits; mode 1: atomicMin of the triangle id
// where the depth equals the minimum; raster_small: one invocation per small triangle, raster: one
// workgroup per (triangle, tile) pair) -> shade (per pixel: perspective-correct UVs, trilinear
// mip-mapped sRGB RGBA8 texture, ambient + Lambert, depth).
#ifndef EVF_SIM_LAYOUT_H
#define EVF_SIM_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kSimSetupGroupSize, 64u)
EVF_CONST(uint, kSimTile, 16u)              // raster tile edge (pixels); one workgroup per tile
EVF_CONST(uint, kSimTileRows, 8u)           // sim/raster: pixels a tile-column invocation tests (divides kSimTile)
EVF_CONST(uint, kSimShadeGroupSize, 64u)
EVF_CONST(uint, kSimDecodeEntries, 256u)  // sim/shade's sRGB decode table, four values a texel
EVF_CONST(uint, kSimSmallGroupSize, 64u)
// Default of SimPC.misc.z: triangles whose pixel box is at most this many pixels wide and high get
// one invocation each (sim/raster_small) instead of a workgroup per tile.
EVF_CONST(uint, kSimSmallBox, 8u)
EVF_CONST(uint, kSimNoTriangle, 0xFFFFFFFFu)
EVF_CONST(uint, kSimNoTexture, 0xFFFFFFFFu)

// One triangle in world space (std430: 5 vec4 = 80 bytes).
struct SimTriangle {
  vec4 p0;   // xyz, w = material index (as float, exact below 2^24)
  vec4 p1;
  vec4 p2;
  vec4 uv01; // u0 v0 u1 v1
  vec4 uv2;  // u2 v2, 0, 0
};

// A material: base colour factor (linear RGBA) and its base-colour texture.
struct SimMaterial {
  vec4 factor;
  uvec4 tex;  // x: first texel in the texel buffer (kSimNoTexture = none), y: width, z: height,
              // w: wrap modes (bits 0-1 s, 2-3 t: 0 repeat, 1 clamp, 2 mirrored repeat), bits 8-15:
              // mip levels (level l: max(1, width >> l) x max(1, height >> l) texels, stored after l - 1)
};

struct SimPC {
  vec4 r0;      // world_to_camera rows, translation in w
  vec4 r1;
  vec4 r2;
  vec4 intr;    // fx fy cx cy
  vec4 light;   // xyz: unit direction towards the light (world), w: ambient fraction
  vec4 background;  // linear RGB, a: unused
  uvec4 dims;   // width, height, triangle count, raster mode (0 depth, 1 id)
  vec4 misc;    // x: near plane, y: texture supersampling (1 or 4 samples per pixel), z: small-triangle box
                // limit in pixels (0: every triangle takes the tiles)
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// sim/raster
EVF_BIND(kSimRasterBindCamVerts, 0u, CamVerts)
EVF_BIND(kSimRasterBindBoxes, 1u, Boxes)
EVF_BIND(kSimRasterBindOffsets, 2u, Offsets)
EVF_BIND(kSimRasterBindDepth, 3u, Depth)
EVF_BIND(kSimRasterBindIds, 4u, Ids)
// sim/shade
EVF_BIND(kSimShadeBindTris, 0u, Tris)
EVF_BIND(kSimShadeBindCamVerts, 1u, CamVerts)
EVF_BIND(kSimShadeBindIds, 2u, Ids)
EVF_BIND(kSimShadeBindMaterials, 3u, Materials)
EVF_BIND(kSimShadeBindTexels, 4u, Texels)  // packed sRGB RGBA8 texels, read as R32UI texels
EVF_BIND(kSimShadeBindOut, 5u, Out)
EVF_BIND(kSimShadeBindDecode, 6u, Decode)  // kSimDecodeEntries linear values of the 8-bit sRGB codes
// sim/tri_setup
EVF_BIND(kSimTriSetupBindTris, 0u, Tris)
EVF_BIND(kSimTriSetupBindCamVerts, 1u, CamVerts)
EVF_BIND(kSimTriSetupBindBoxes, 2u, Boxes)
EVF_BIND(kSimTriSetupBindCounts, 3u, Counts)

EVF_NAMESPACE_END
#endif
