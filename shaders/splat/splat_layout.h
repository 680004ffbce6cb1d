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
EVF_CONST(uint, kPoseReduceGroupSize, 256u)
EVF_CONST(uint, kFlagAntialiased, 1u)
EVF_CONST(uint, kFlagAccumulate, 2u)   // set when backward accumulates (the shader is the project_bwd_acc build)
// Sort keys: tile << depth_bits | the depth's top depth_bits bits, at least kDepthKeyBitsMin of
// them (so that equal keys are rare: splat/depth_runs orders those by the depths themselves).
EVF_CONST(uint, kDepthKeyBitsMin, 15u)
EVF_CONST(uint, kDepthRunsGroupSize, 64u)
EVF_CONST(uint, kDepthRunsSpan, 32u)  // sorted positions per invocation of splat/depth_runs (<= 32)

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
  uint slot;         // where the sum goes: Pose[6 slot .. 6 slot + 6)
  uint pad0, pad1;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// splat/emit
EVF_BIND(kEmitBindProjA, 0u, ProjA)
EVF_BIND(kEmitBindProjB, 1u, ProjB)
EVF_BIND(kEmitBindRect, 2u, Rect)
EVF_BIND(kEmitBindOffsets, 3u, Offsets)
EVF_BIND(kEmitBindKeys, 4u, Keys)
EVF_BIND(kEmitBindGid, 6u, Gid)
// splat/project, splat/project_bwd
EVF_BIND(kParamBindMeans, 0u, Means)
EVF_BIND(kParamBindLogScales, 1u, LogScales)
EVF_BIND(kParamBindQuats, 2u, Quats)
EVF_BIND(kParamBindOpacities, 3u, Opacities)
EVF_BIND(kParamBindSh0, 4u, Sh0)
EVF_BIND(kParamBindSh1, 5u, Sh1)
EVF_BIND(kParamBindSh2, 6u, Sh2)
EVF_BIND(kParamBindSh3, 7u, Sh3)
// splat/pose_reduce
EVF_BIND(kPoseReduceBindPartials, 0u, Partials)
EVF_BIND(kPoseReduceBindPose, 1u, Pose)
// splat/project
EVF_BIND(kProjectBindProjA, 8u, ProjA)
EVF_BIND(kProjectBindProjB, 9u, ProjB)
EVF_BIND(kProjectBindProjC, 10u, ProjC)
EVF_BIND(kProjectBindRect, 11u, Rect)
EVF_BIND(kProjectBindCount, 12u, Count)
EVF_BIND(kProjectBindDColor, 13u, DColor)
// splat/project_bwd
EVF_BIND(kProjectBwdBindOffsets, 8u, Offsets)
// Per-slot gradients of the compositing, written by rasterize_bwd*, summed per Gaussian here:
// G0[slot] = (v_mean2d.xy, v_conic.xy), G1[slot] = (v_conic.z, v_opacity, v_rgb.rg) as vec4s,
// G2[slot] = v_rgb.b (three accesses per slot: CPU drivers loop over the lanes for each).
EVF_BIND(kProjectBwdBindG0, 10u, G0)
EVF_BIND(kProjectBwdBindG1, 11u, G1)
EVF_BIND(kProjectBwdBindG2, 12u, G2)
EVF_BIND(kProjectBwdBindVMeans, 19u, VMeans)
EVF_BIND(kProjectBwdBindVLogScales, 20u, VLogScales)
EVF_BIND(kProjectBwdBindVQuats, 21u, VQuats)
EVF_BIND(kProjectBwdBindVOpacities, 22u, VOpacities)
EVF_BIND(kProjectBwdBindVSh0, 23u, VSh0)
EVF_BIND(kProjectBwdBindVSh1, 24u, VSh1)
EVF_BIND(kProjectBwdBindVSh2, 25u, VSh2)
EVF_BIND(kProjectBwdBindVSh3, 26u, VSh3)
EVF_BIND(kProjectBwdBindGrad2d, 27u, Grad2d)
EVF_BIND(kProjectBwdBindPosePartial, 28u, PosePartial)
EVF_BIND(kProjectBwdBindProjC, 29u, ProjC)
EVF_BIND(kProjectBwdBindDColor, 30u, DColor)
// splat/project_bwd_acc_block only: texel views of the gradient buffers it adds to (VMeans ...
// Grad2d, the same buffers), read before each element is written.
EVF_BIND(kProjectBwdBindVMeansIn, 31u, VMeansIn)
EVF_BIND(kProjectBwdBindVLogScalesIn, 32u, VLogScalesIn)
EVF_BIND(kProjectBwdBindVQuatsIn, 33u, VQuatsIn)
EVF_BIND(kProjectBwdBindVOpacitiesIn, 34u, VOpacitiesIn)
EVF_BIND(kProjectBwdBindVSh0In, 35u, VSh0In)
EVF_BIND(kProjectBwdBindGrad2dIn, 36u, Grad2dIn)
// splat/rasterize, splat/rasterize_block, splat/rasterize_bwd, splat/rasterize_bwd_block
// (written by splat/tile_ranges, or by splat/rasterize_block itself)
EVF_BIND(kRasterBindRanges, 0u, Ranges)
EVF_BIND(kRasterBindSlots, 1u, Slots)
EVF_BIND(kRasterBindGid, 2u, Gid)
EVF_BIND(kRasterBindProjA, 3u, ProjA)
EVF_BIND(kRasterBindProjB, 4u, ProjB)
EVF_BIND(kRasterBindProjC, 5u, ProjC)
// splat/rasterize, splat/rasterize_block
EVF_BIND(kRasterizeBindOutRgb, 6u, OutRgb)
EVF_BIND(kRasterizeBindOutAlpha, 7u, OutAlpha)
EVF_BIND(kRasterizeBindOutDepth, 8u, OutDepth)
// final_T and last_isect (one past the last blended): per pixel, in image order for the
// per-pixel kernels; tile by tile for the block kernels (tile t's pixel (x, y) at
// t * 256 + y * 16 + x, so a block's row of 4 is one vec4), tiles_x * tiles_y * 256 entries.
EVF_BIND(kRasterizeBindOutT, 9u, OutT)
EVF_BIND(kRasterizeBindOutLast, 10u, OutLast)
// Block kernels only: for each 32-entry word of a tile's list that the forward loaded (entries
// range.x + 32 w ... + 31), the bit set of its entries in each of the forward's kForwardBlocks
// blocks of 4 x 4 pixels (support_blocks): kForwardBlocks uints from kForwardBlocks *
// ((range.x + 32 w) / 32 + tile), distinct for every word of every tile, so the plane holds
// kForwardBlocks * (entries / 32 + tiles + 1) uints. Written by the forward, read by the backward,
// which reads only words the forward loaded (those before its tile's last blended entry).
EVF_BIND(kRasterizeBindOutBlocks, 11u, OutBlocks)
EVF_CONST(uint, kForwardBlocks, 16u)
// Block forward only: the sorted keys, in which each tile's workgroup finds its own range (a
// binary search) and writes it to Ranges for the backward, in place of splat/tile_ranges.
EVF_BIND(kRasterizeBindSortedKeys, 12u, SortedKeys)
// splat/rasterize_bwd, splat/rasterize_bwd_block
EVF_BIND(kRasterizeBwdBindInT, 6u, InT)
EVF_BIND(kRasterizeBwdBindInLast, 7u, InLast)
EVF_BIND(kRasterizeBwdBindVRgb, 8u, VRgb)
EVF_BIND(kRasterizeBwdBindVAlpha, 9u, VAlpha)
EVF_BIND(kRasterizeBwdBindG0, 10u, G0)
EVF_BIND(kRasterizeBwdBindG1, 11u, G1)
EVF_BIND(kRasterizeBwdBindG2, 12u, G2)
EVF_BIND(kRasterizeBwdBindInBlocks, 13u, InBlocks)  // block kernel only (kRasterizeBindOutBlocks)
// splat/depth_runs
EVF_BIND(kDepthRunsBindKeys, 0u, Keys)
EVF_BIND(kDepthRunsBindSlots, 1u, Slots)
EVF_BIND(kDepthRunsBindGid, 2u, Gid)
EVF_BIND(kDepthRunsBindProjB, 3u, ProjB)
EVF_BIND(kDepthRunsBindSlotsIn, 4u, SlotsIn)  // "_block" build: a texel view of Slots
// splat/tile_ranges
EVF_BIND(kTileRangesBindKeys, 0u, Keys)
EVF_BIND(kTileRangesBindRanges, 1u, Ranges)

EVF_NAMESPACE_END
#endif
