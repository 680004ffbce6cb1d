// Buffers shared by rasterize and rasterize_bwd (bindings 0..5), and the batch of Gaussians a
// tile's workgroup holds in shared memory (per-pixel kernels) or the blocks it splits into
// (block kernels).
#ifdef EVF_RANGES_OUT
layout(std430, binding = kRasterBindRanges) writeonly buffer Ranges { uvec2 tile_range[]; };
#else
layout(std430, binding = kRasterBindRanges) readonly buffer Ranges { uvec2 tile_range[]; };
#endif
#ifdef EVF_BLOCK_BATCH
// The block kernels (CPU drivers) read the sorted slots, the Gaussian ids and the projected
// Gaussians as texel buffers, at every visit: on lavapipe a texel fetch at a different index in
// each SIMD lane is straight-line code (the 32-bit ones one hardware gather), where a load from a
// storage buffer or from shared memory is a loop over the lanes.
layout(binding = kRasterBindSlots) uniform usamplerBuffer Slots;
layout(binding = kRasterBindGid) uniform usamplerBuffer Gid;
layout(binding = kRasterBindProjA) uniform samplerBuffer ProjA;  // mean.xy, conic.xy
layout(binding = kRasterBindProjB) uniform samplerBuffer ProjB;  // conic.z, opacity, depth, q_max
layout(binding = kRasterBindProjC) uniform samplerBuffer ProjC;  // rgb, 0
uint slot_of_isect(uint isect) { return texelFetch(Slots, int(isect)).x; }
uint gaussian_of_isect(uint isect) { return texelFetch(Gid, int(slot_of_isect(isect))).x; }
vec4 proj_a(uint g) { return texelFetch(ProjA, int(g)); }
vec4 proj_b(uint g) { return texelFetch(ProjB, int(g)); }
vec4 proj_c(uint g) { return texelFetch(ProjC, int(g)); }
#else
layout(std430, binding = kRasterBindSlots) readonly buffer Slots { uint slot_from_isect[]; };     // sorted
layout(std430, binding = kRasterBindGid) readonly buffer Gid { uint gaussian_id_from_slot[]; };
layout(std430, binding = kRasterBindProjA) readonly buffer ProjA { vec4 proj_mean_conic[]; };
layout(std430, binding = kRasterBindProjB) readonly buffer ProjB { vec4 proj_misc[]; };
layout(std430, binding = kRasterBindProjC) readonly buffer ProjC { vec4 proj_color[]; };
#endif

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
// of 4 x EVF_ROWS pixels, one per invocation. Each batch of the tile's Gaussians comes with the
// blocks each one's support reaches (support_blocks: computed by the forward, kept as each
// 32-entry word's bit set per block for the backward, block_word_index), so that each invocation
// visits only those; a visit fetches the Gaussian's projection itself (gaussian_of_isect,
// proj_a/b/c).
#if EVF_BLOCKS > 32
#error a Gaussian's blocks are one uint
#endif

// Half extents of the support {d : d^T conic d <= q_max}: its bounding box is
// sqrt(q_max * diag(inverse(conic))). Padded so that float rounding never drops a pixel whose
// alpha reaches 1/255; the per-pixel alpha test stays the exact one.
vec2 support_half_extent(vec3 conic, float q_max) {
  float det = conic.x * conic.z - conic.y * conic.y;
  return sqrt(max(q_max, 0.0) * vec2(conic.z, conic.x) / det) * (1.0 + 4.0 * kBoxPad) + 0.01;
}

// Columns [c0, c1) of the blocks in a row of blocks that the support {d : d^T conic d <= q} can
// reach, for pixel centres y - mean.y in [dy0, dy1]. For a fixed dy the support spans
// dx in -conic.y dy / conic.x -+ sqrt(q conic.x - det dy^2) / conic.x; its right end is concave in
// dy and peaks at dx = ex (the rightmost point, dy = -conic.y ex / conic.z), its left end convex
// with the trough -ex at dy = conic.y ex / conic.z, so over the band each end is that extreme or
// the value at the band's nearer edge. `mx`: the mean's x in tile coordinates; `ex`, `ey`: the
// support's half extents for q. Widened like the box against float rounding.
uvec2 support_cols(float mx, vec3 conic, float q, float det, float ex, float ey, float dy0, float dy1) {
  float lo_dy = max(dy0, -ey), hi_dy = min(dy1, ey);
  if (lo_dy > hi_dy) return uvec2(0u);
  vec2 dy = vec2(lo_dy, hi_dy);
  vec2 centre = -conic.y * dy / conic.x;
  vec2 half_w = sqrt(max(q * conic.x - det * dy * dy, vec2(0.0))) / conic.x;
  float peak = conic.y * ex / conic.z;  // dy of the leftmost point; the rightmost is at -peak
  float right = (-peak >= lo_dy && -peak <= hi_dy) ? ex : max(centre.x + half_w.x, centre.y + half_w.y);
  float left = (peak >= lo_dy && peak <= hi_dy) ? -ex : min(centre.x - half_w.x, centre.y - half_w.y);
  float pad = 4.0 * kBoxPad * ex + 0.01;
  float c0 = clamp(ceil((mx + left - pad - 3.5) / 4.0), 0.0, 4.0);
  float c1 = clamp(floor((mx + right + pad - 0.5) / 4.0) + 1.0, 0.0, 4.0);
  return uvec2(c0, max(c0, c1));
}

// The blocks (bit r * 4 + c: row r, column c of blocks) that hold a pixel centre of the support
// of a Gaussian with mean `mean` (tile coordinates), conic and q_max: rows of blocks from the
// support's bounding box, the columns of each row from the support over that row (support_cols).
uint support_blocks(vec2 mean, vec3 conic, float q_max) {
  vec2 ext = support_half_extent(conic, q_max);
  // Block row r holds pixel centres y in [R r + 0.5, R r + R - 0.5], R = EVF_ROWS.
  float rows = float(EVF_ROWS), nrows = float(EVF_BLOCKS / 4);
  uint r0 = uint(clamp(ceil((mean.y - ext.y - (rows - 0.5)) / rows), 0.0, nrows));
  uint r1 = uint(clamp(floor((mean.y + ext.y - 0.5) / rows) + 1.0, 0.0, nrows));
  float q = max(q_max, 0.0) * (1.0 + 8.0 * kBoxPad);
  float det = conic.x * conic.z - conic.y * conic.y;
  float ex = sqrt(q * conic.z / det), ey = sqrt(q * conic.x / det);
  uint mask = 0u;
  for (uint r = r0; r < r1; ++r) {
    float y0 = rows * float(r) + 0.5 - mean.y;
    uvec2 c = support_cols(mean.x, conic, q, det, ex, ey, y0 - 0.01, y0 + rows - 1.0 + 0.01);
    mask |= (((1u << c.y) - 1u) & ~((1u << c.x) - 1u)) << (4u * r);
  }
  return mask;
}

// Where the bit sets of the 32-entry word of tile `tile`'s list that starts at sorted position
// `first` lie in the block-word plane, in units of kForwardBlocks uints (splat_layout.h). Within
// a tile, first / 32 grows by one a word; the next tile's first word starts past the last one,
// and the added tile index keeps two tiles' words apart when they share a multiple of 32.
uint block_word_index(uint first, uint tile) { return (first >> 5u) + tile; }

// The vec4 of the first of block `lid`'s runs in the tile-by-tile planes (final_T, last_isect:
// splat_layout.h); its run i is 4 i further on.
uint block_run_vec4(ivec2 tile, uint tiles_x, uint lid) {
  uint tile_vec4s = kTileSize * kTileSize / 4u;
  return (uint(tile.y) * tiles_x + uint(tile.x)) * tile_vec4s + (lid / 4u) * EVF_ROWS * 4u + lid % 4u;
}
#endif

ivec2 tile_of_group(uint tiles_x) {
  uint t = evf_linear_group();
  return ivec2(t % tiles_x, t / tiles_x);
}
