#version 450
// Key emission: one invocation per Gaussian. Writes one key per tile its support meets, at slots
// [offset[g], offset[g+1]) — the tiles project.comp counted, from its mask or by the same exact
// test — and the slot's Gaussian. The sort makes the slots' order itself
// (RadixSort::record_order): no value is written.
// key = tile id << depth_bits | top bits of the depth remapped to [1, 2).
#extension GL_GOOGLE_include_directive : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
#include "common/texel.glsl"
layout(local_size_x = kProjectGroupSize) in;
#ifdef EVF_EMIT_TEXELS
// The "_block" build (CPU drivers, beside the block compositing kernels) reads its inputs as texel
// buffers (why: common/texel.glsl).
layout(binding = kEmitBindProjA) uniform samplerBuffer ProjA;
layout(binding = kEmitBindProjB) uniform samplerBuffer ProjB;
layout(binding = kEmitBindRect) uniform usamplerBuffer Rect;        // R32UI, four per Gaussian
layout(binding = kEmitBindOffsets) uniform usamplerBuffer Offsets;  // [N+1]
vec4 proj_a(uint g) { return texelFetch(ProjA, int(g)); }
vec4 proj_b(uint g) { return texelFetch(ProjB, int(g)); }
uvec4 rect_of(uint g) { return evf_texel_uvec4(Rect, g); }
uint offset_of(uint g) { return texelFetch(Offsets, int(g)).x; }
#else
layout(std430, binding = kEmitBindProjA) readonly buffer ProjA { vec4 proj_mean_conic[]; };
layout(std430, binding = kEmitBindProjB) readonly buffer ProjB { vec4 proj_misc[]; };
layout(std430, binding = kEmitBindRect) readonly buffer Rect { uvec4 tile_rect[]; };
layout(std430, binding = kEmitBindOffsets) readonly buffer Offsets { uint isect_offset[]; };  // [N+1]
vec4 proj_a(uint g) { return proj_mean_conic[g]; }
vec4 proj_b(uint g) { return proj_misc[g]; }
uvec4 rect_of(uint g) { return tile_rect[g]; }
uint offset_of(uint g) { return isect_offset[g]; }
#endif
layout(std430, binding = kEmitBindKeys) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = kEmitBindGid) writeonly buffer Gid { uint gaussian_id_from_slot[]; };
layout(push_constant) uniform PC { ProjectPC pc; };

// Slot `slot` holds Gaussian g's key for tile t.
void put_key(uint slot, uint g, uvec2 t, uint depth_key) {
  keys[slot] = ((t.y * pc.tiles_x + t.x) << pc.depth_bits) | depth_key;
  gaussian_id_from_slot[slot] = g;
}

void main() {
  uint g = evf_linear_invocation(kProjectGroupSize);
  if (g >= pc.num_gaussians) return;
  uint begin = offset_of(g), end = offset_of(g + 1u);
  if (begin == end) return;
  vec4 a = proj_a(g), b = proj_b(g);
  vec2 mean2d = a.xy;
  vec3 conic = vec3(a.zw, b.x);
  float q_max = b.w;
  float zr = (2.0 * b.z + 1.0) / (b.z + 1.0);  // monotonic map of depth into [1, 2)
  uint depth_key = (floatBitsToUint(zr) & 0x7FFFFFu) >> (23u - pc.depth_bits);
  uvec2 t0, t1;
  uint mask;
  tile_rect_unpack(rect_of(g), t0, t1, mask);
  uint w = t1.x - t0.x, area = w * (t1.y - t0.y);
  uint slot = begin;
  // Up to kTileMaskTiles tiles: the ones project.comp's test found, from its mask, in the same
  // order. Two loops rather than one with a branch: on CPU drivers a loop ends early, an `if`
  // runs both sides.
  uint m = area <= kTileMaskTiles ? mask : 0u;
  while (m != 0u && slot < end) {
    uint k = uint(findLSB(m));
    m &= m - 1u;
    put_key(slot++, g, t0 + uvec2(k % w, k / w), depth_key);
  }
  // Larger rectangles: each tile tested again, as project.comp counted.
  uint tested = area > kTileMaskTiles ? area : 0u;
  for (uint k = 0u; k < tested; ++k) {
    uint tx = t0.x + k % w, ty = t0.y + k / w;
    vec2 lo = vec2(tx * kTileSize, ty * kTileSize) + 0.5, hi = lo + float(kTileSize - 1);
    if (slot < end && ellipse_meets_rect(mean2d, conic, q_max, lo, hi)) put_key(slot++, g, uvec2(tx, ty), depth_key);
  }
  for (; slot < end; ++slot) {  // only if the two passes disagreed: never read as a tile
    keys[slot] = pc.sentinel_key;
    gaussian_id_from_slot[slot] = 0xFFFFFFFFu;
  }
}
