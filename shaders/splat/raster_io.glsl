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
// of 4 x EVF_ROWS pixels, one per invocation. Each loaded Gaussian comes with the blocks its
// support reaches (support_blocks: computed by the forward, kept per intersection for the
// backward), so that each invocation visits only those. A visit reads 9 (backward) or 10
// (forward) floats in three accesses (each a loop over the SIMD lanes on lavapipe), so nothing
// else is kept.
#ifndef EVF_BATCH
#define EVF_BATCH 256  // Gaussians per batch, a multiple of 32
#endif
shared vec4 batch_a[EVF_BATCH];  // mean.xy, conic.xy
shared vec4 batch_b[EVF_BATCH];  // conic.z, opacity, red, green
shared vec2 batch_c[EVF_BATCH];  // blue, depth
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

// Loads Gaussian `isect` of the tile as batch entry `local`; returns what support_blocks needs:
// (mean.xy, conic.xy) and (conic.z, opacity, depth, q_max).
void load_batch_values(uint local, uint isect, out vec4 a, out vec4 b) {
  uint g = gaussian_id_from_slot[slot_from_isect[isect]];
  a = proj_mean_conic[g];
  b = proj_misc[g];
  vec3 col = proj_color[g].rgb;
  batch_a[local] = a;
  batch_b[local] = vec4(b.xy, col.rg);
  batch_c[local] = vec2(col.b, b.z);
}

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
