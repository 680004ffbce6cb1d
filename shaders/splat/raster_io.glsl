// Buffers shared by rasterize and rasterize_bwd (bindings 0..5), and the batch of Gaussians a
// tile's workgroup holds in shared memory.
layout(std430, binding = kRasterBindRanges) readonly buffer Ranges { uvec2 tile_range[]; };
layout(std430, binding = kRasterBindSlots) readonly buffer Slots { uint slot_from_isect[]; };     // sorted
layout(std430, binding = kRasterBindGid) readonly buffer Gid { uint gaussian_id_from_slot[]; };
layout(std430, binding = kRasterBindProjA) readonly buffer ProjA { vec4 proj_mean_conic[]; };
layout(std430, binding = kRasterBindProjB) readonly buffer ProjB { vec4 proj_misc[]; };
layout(std430, binding = kRasterBindProjC) readonly buffer ProjC { vec4 proj_color[]; };

#ifndef EVF_BLOCK_BATCH
shared vec4 batch_mean_conic[256];  // mean.xy, conic.xy
shared vec4 batch_misc[256];        // conic.z, opacity, depth, -
shared vec3 batch_color[256];
shared uint batch_slot[256];

void load_batch_entry(uint local, uint isect) {
  uint slot = slot_from_isect[isect];
  uint g = gaussian_id_from_slot[slot];
  batch_slot[local] = slot;
  batch_mean_conic[local] = proj_mean_conic[g];
  batch_misc[local] = proj_misc[g];
  batch_color[local] = proj_color[g].rgb;
}
#else
// Block kernels (rasterize_block, rasterize_bwd_block): the tile is split into EVF_BLOCKS blocks
// of 4 x EVF_ROWS pixels, one per invocation. Loading a batch also records, per block, which of
// the batch's Gaussians can reach it (a 256-bit set per block), so that each invocation visits
// only those. A visit reads 9 (backward) or 10 (forward) floats: each float read is a loop over
// the SIMD lanes on lavapipe, so nothing else is kept.
#ifndef EVF_BATCH
#define EVF_BATCH 256  // Gaussians per batch, a multiple of 32
#endif
shared vec4 batch_a[EVF_BATCH];  // mean.xy, conic.xy
shared vec4 batch_b[EVF_BATCH];  // conic.z, opacity, red, green
shared vec2 batch_c[EVF_BATCH];  // blue, depth
shared uint block_bits[EVF_BLOCKS][EVF_BATCH / 32];

// Half extents of the support {d : d^T conic d <= q_max}: its bounding box is
// sqrt(q_max * diag(inverse(conic))). Padded so that float rounding never drops a pixel whose
// alpha reaches 1/255; the per-pixel alpha test stays the exact one.
vec2 support_half_extent(vec3 conic, float q_max) {
  float det = conic.x * conic.z - conic.y * conic.y;
  return sqrt(max(q_max, 0.0) * vec2(conic.z, conic.x) / det) * (1.0 + 4.0 * kBoxPad) + 0.01;
}

// Loads Gaussian `isect` of the tile as batch entry `local` and marks the blocks whose pixel
// centres its bounding box covers. `tile_origin`: the tile's first pixel.
void load_batch_entry(uint local, uint isect, vec2 tile_origin) {
  uint g = gaussian_id_from_slot[slot_from_isect[isect]];
  vec4 a = proj_mean_conic[g], b = proj_misc[g];
  vec3 conic = vec3(a.zw, b.x);
  vec2 ext = support_half_extent(conic, b.w);
  vec3 col = proj_color[g].rgb;
  batch_a[local] = a;
  batch_b[local] = vec4(b.xy, col.rg);
  batch_c[local] = vec2(col.b, b.z);
  // Block column c holds pixel centres x in [4c + 0.5, 4c + 3.5] (tile coordinates); rows alike.
  vec2 m = a.xy - tile_origin, bsize = vec2(4.0, float(EVF_ROWS));
  vec2 nblk = vec2(4.0, float(EVF_BLOCKS / 4));
  vec2 lo = clamp(ceil((m - ext - (bsize - 0.5)) / bsize), vec2(0.0), nblk);
  vec2 hi = clamp(floor((m + ext - 0.5) / bsize), vec2(-1.0), nblk - 1.0);
  uint c0 = uint(lo.x), c1 = uint(hi.x + 1.0), r0 = uint(lo.y), r1 = uint(hi.y + 1.0);
  if (c0 >= c1) return;
  uint cols = ((1u << c1) - 1u) & ~((1u << c0) - 1u);
  uint bit = 1u << (local & 31u);
  for (uint r = r0; r < r1; ++r) {
    uint m4 = cols;
    while (m4 != 0u) {
      uint c = uint(findLSB(m4));
      m4 &= m4 - 1u;
      atomicOr(block_bits[r * 4u + c][local >> 5], bit);
    }
  }
}
#endif

ivec2 tile_of_group(uint tiles_x) {
  uint t = evf_linear_group();
  return ivec2(t % tiles_x, t / tiles_x);
}
