#version 450
// Forward rasterization for CPU drivers: one workgroup per 16x16 tile, each invocation owns a
// block of 4 x EVF_ROWS pixels (rows of 4 held as vec4s) and visits, front to back, only the
// Gaussians whose support reaches a pixel centre of its block (support_blocks in raster_io.glsl).
// Same result as rasterize.comp, pixel for pixel; see docs/rasterizer.md.
// EVF_NO_DEPTH (the "_nodepth" build, for renders whose depth nothing reads: RenderSettings::depth)
// keeps no depth sum and has no depth plane: one vec4 less of each run's state through the walk.
// Why: lavapipe runs the invocations of a SIMD vector in lockstep with masks (an `if` skips
// nothing; only loops end early) and turns every storage or shared-memory access into a loop
// over the lanes. So each invocation walks its own list, fetching each Gaussian it visits as
// texels (straight-line code whatever index each lane reads), and one fetch of a Gaussian serves
// 4 x EVF_ROWS pixels.
#extension GL_GOOGLE_include_directive : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
#ifndef EVF_ROWS
#define EVF_ROWS 4
#endif
// 4 rows measured best on lavapipe (bench raster 100k: 2 and 8 rows slower or equal).
// EVF_RUNS(X) expands X(i) for each row i of the block; EVF_QUADS(X) X(k) for each group of four
// rows (block_exp).
#if EVF_ROWS == 4
#define EVF_RUNS(X) X(0) X(1) X(2) X(3)
#define EVF_QUADS(X) X(0)
#elif EVF_ROWS == 8
#define EVF_RUNS(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6) X(7)
#define EVF_QUADS(X) X(0) X(1)
#else
#error EVF_ROWS must be 4 or 8
#endif
#define EVF_THREADS (64 / EVF_ROWS)
#define EVF_BLOCKS EVF_THREADS
layout(local_size_x = EVF_THREADS) in;
#define EVF_BLOCK_BATCH 1
// Batches of 256, loaded a 32-entry word per invocation (raster_io.glsl): 64, 128, 256 and 512
// measured on bench raster 100k, 256 best. (With one shared atomic per entry and block, the
// loading cost more and 64 was best: a tile stops loading sooner once all its blocks are opaque.)
#ifndef EVF_BATCH
#define EVF_BATCH 256
#endif
#define EVF_RANGES_OUT 1
#include "splat/raster_io.glsl"
layout(std430, binding = kRasterizeBindOutRgb) writeonly buffer OutRgb { float out_rgb[]; };        // [3][H][W]
layout(std430, binding = kRasterizeBindOutAlpha) writeonly buffer OutAlpha { float out_alpha[]; };  // [H][W]
#ifndef EVF_NO_DEPTH
layout(std430, binding = kRasterizeBindOutDepth) writeonly buffer OutDepth { float out_depth[]; };  // [H][W]
#endif
// Tile by tile (splat_layout.h): a run is one vec4.
layout(std430, binding = kRasterizeBindOutT) writeonly buffer OutT { vec4 final_T[]; };
layout(std430, binding = kRasterizeBindOutLast) writeonly buffer OutLast { uvec4 last_isect[]; };
layout(std430, binding = kRasterizeBindOutBlocks) writeonly buffer OutBlocks { uvec4 block_words[]; };
layout(binding = kRasterizeBindSortedKeys) uniform usamplerBuffer SortedKeys;
layout(push_constant) uniform PC { RasterPC pc; };
shared uint done_count;
shared uint block_bits[EVF_BLOCKS][EVF_BATCH / 32];
#if EVF_BATCH > 32 * EVF_THREADS
#error a batch is loaded one 32-entry word per invocation
#endif
#if EVF_BLOCKS != 16 || EVF_BATCH % 32 != 0
#error the block-word plane holds kForwardBlocks blocks of 4 x 4 a word, words of 32 from each batch's start
#endif

// The first sorted position whose key is at least `key` (pc.num_isects if none). The same index in
// every lane: each step is one texel fetch.
uint first_key_at_least(uint key) {
  uint lo = 0u, hi = pc.num_isects;
  while (lo < hi) {
    uint mid = (lo + hi) >> 1u;
    if (texelFetch(SortedKeys, int(mid)).x < key)
      lo = mid + 1u;
    else
      hi = mid;
  }
  return lo;
}

// The tile's run of the sorted list (keys tile << depth_bits | depth; tile + 1 < 2^tile_bits, so
// the bound does not overflow), kept for the backward. An empty tile gets an empty range.
uvec2 find_tile_range(uint tile, uint lid) {
  uvec2 range = uvec2(first_key_at_least(tile << pc.depth_bits), first_key_at_least((tile + 1u) << pc.depth_bits));
  if (lid == 0u) tile_range[tile] = range;
  return range;
}

// Finds the blocks of the batch's entries [32 w, min(32 w + 32, n)), the tile's Gaussians from
// `start` on, and writes word w of every block's bit set, to shared memory and, for the backward,
// to the block-word plane (block_word_index). One invocation builds a whole word in registers and
// stores it: no shared atomics (each is a loop over the SIMD lanes on lavapipe), EVF_BLOCKS / 4
// vec4 stores per 32 entries to the plane instead of one per entry.
void load_batch_word(uint w, uint start, uint n, vec2 tile_origin, uint tile) {
  uvec4 q[EVF_BLOCKS / 4];  // q[i][k]: block 4 i + k
  for (uint i = 0u; i < EVF_BLOCKS / 4; ++i) q[i] = uvec4(0u);
  uint e_end = min(32u, n - 32u * w);
  for (uint e = 0u; e < e_end; ++e) {
    uint g = gaussian_of_isect(start + 32u * w + e);
    vec4 a = proj_a(g), b = proj_b(g);
    uvec4 m = uvec4(support_blocks(a.xy - tile_origin, vec3(a.zw, b.x), b.w));
    for (uint i = 0u; i < EVF_BLOCKS / 4; ++i) q[i] |= ((m >> (4u * i + uvec4(0u, 1u, 2u, 3u))) & 1u) << e;
  }
  uint plane = block_word_index(start + 32u * w, tile) * (kForwardBlocks / 4u);
  for (uint i = 0u; i < EVF_BLOCKS / 4; ++i) {
    block_words[plane + i] = q[i];
    for (uint k = 0u; k < 4u; ++k) block_bits[4u * i + k][w] = q[i][k];
  }
}

struct Run {     // 4 horizontally adjacent pixels
  vec4 T;  // transmittance; negated once the pixel is done (one vec4 less through the walk)
  vec4 Cr, Cg, Cb;
#ifndef EVF_NO_DEPTH
  vec4 D;
#endif
  uvec4 last;
};

Run run_init(ivec2 p0, uint first) {
  Run r;
  bvec4 outside = not(lessThan(ivec4(p0.x) + ivec4(0, 1, 2, 3), ivec4(pc.width)));
  if (p0.y >= int(pc.height)) outside = bvec4(true);
  r.T = mix(vec4(1.0), vec4(-1.0), outside);
  r.Cr = r.Cg = r.Cb = vec4(0.0);
#ifndef EVF_NO_DEPTH
  r.D = vec4(0.0);
#endif
  r.last = uvec4(first);
  return r;
}

// Blends Gaussian `idx` (already read) into the run; `G`: its exp(power) at the run's pixels
// (block_exp).
void blend(inout Run r, vec4 G, float opacity, vec3 col, float depth, uint idx) {
  vec4 alpha = min(vec4(kAlphaMax), opacity * G);
  bvec4 use = greaterThan(r.T, vec4(0.0));
  use = bvec4(uvec4(use) & uvec4(greaterThanEqual(alpha, vec4(kAlphaMin))));
  vec4 next_T = r.T * (1.0 - alpha);
  bvec4 stop = bvec4(uvec4(use) & uvec4(lessThan(next_T, vec4(kTransmittanceMin))));
  use = bvec4(uvec4(use) & ~uvec4(stop));
  vec4 w = mix(vec4(0.0), alpha * r.T, use);  // adding 0 w leaves a sum as it is
  r.Cr += w * col.r;
  r.Cg += w * col.g;
  r.Cb += w * col.b;
#ifndef EVF_NO_DEPTH
  r.D += w * depth;
#endif
  r.T = mix(mix(r.T, next_T, use), -r.T, stop);
  r.last = mix(r.last, uvec4(idx + 1u), use);
}

// `q`: the run's vec4 in the tile-by-tile planes.
void store_run(Run r, ivec2 p0, uint q) {
  r.T = abs(r.T);
  final_T[q] = r.T;
  last_isect[q] = r.last;
  if (p0.y >= int(pc.height)) return;
  uint hw = pc.width * pc.height;
  for (int k = 0; k < 4; ++k) {
    if (p0.x + k >= int(pc.width)) break;
    uint i = uint(p0.y) * pc.width + uint(p0.x + k);
    float T = r.T[k];
    out_rgb[i] = r.Cr[k] + T * pc.background.r;
    out_rgb[hw + i] = r.Cg[k] + T * pc.background.g;
    out_rgb[2 * hw + i] = r.Cb[k] + T * pc.background.b;
    out_alpha[i] = 1.0 - T;
#ifndef EVF_NO_DEPTH
    out_depth[i] = (T < 1.0) ? r.D[k] / (1.0 - T) : 0.0;
#endif
  }
}

bool run_done(Run r) { return all(lessThan(r.T, vec4(0.0))); }

void main() {
  ivec2 tile = tile_of_group(pc.tiles_x);
  uint lid = gl_LocalInvocationIndex;
  // Block of 4 x EVF_ROWS pixels: 4 blocks per tile row.
  ivec2 p0 = tile * int(kTileSize) + ivec2(int(lid % 4u) * 4, int(lid / 4u) * EVF_ROWS);
  float cxm = float(p0.x) + 2.0;  // the middle of the block's columns
  float cy = float(p0.y) + 0.5;
  vec2 tile_origin = vec2(tile * int(kTileSize));
  uint tile_index = uint(tile.y) * pc.tiles_x + uint(tile.x);
  uvec2 range = find_tile_range(tile_index, lid);
#define EVF_INIT(i) Run r##i = run_init(p0 + ivec2(0, i), range.x);
  EVF_RUNS(EVF_INIT)
#define EVF_DONE(i) && run_done(r##i)
#define EVF_EXP(k) block_exp(conic, dxm, a.y - (cy + (4.0 * k + 1.5)), G[4 * k], G[4 * k + 1], G[4 * k + 2], G[4 * k + 3]);
#define EVF_BLEND(i) blend(r##i, G[i], opacity, col, b.z, start + j);
// Blends the next entry of the bit set into every run; with `found` false, entry 0 with opacity 0.
// `found` is read once, into `live`, before the entry is taken from `bits` (it may test `bits`).
#define EVF_VISIT(found)                                          \
  {                                                               \
    bool live = found;                                            \
    uint j = live ? w * 32u + uint(findLSB(bits)) : 0u;           \
    bits &= bits - 1u;                                            \
    uint g = gaussian_of_isect(start + j);                        \
    vec4 a = proj_a(g), b = proj_b(g);                            \
    vec3 conic = vec3(a.zw, b.x), col = proj_c(g).rgb;            \
    float opacity = live ? b.y : 0.0;                             \
    float dxm = a.x - cxm;                                        \
    vec4 G[EVF_ROWS];                                             \
    EVF_QUADS(EVF_EXP)                                            \
    EVF_RUNS(EVF_BLEND)                                           \
  }
  for (uint start = range.x; start < range.y; start += EVF_BATCH) {
    uint n = min(uint(EVF_BATCH), range.y - start);
    barrier();
    if (lid == 0) done_count = 0;
    bool done = true EVF_RUNS(EVF_DONE);
    barrier();
    if (32u * lid < n) load_batch_word(lid, start, n, tile_origin, tile_index);
    if (done) atomicAdd(done_count, 1u);
    barrier();
    if (done_count == EVF_THREADS) break;
    // This block's Gaussians, front to back, from its bit set. One loop over the whole batch
    // (not one per 32-bit word): the lanes of a SIMD vector run as many iterations as their
    // busiest lane, and per batch that is fewer than the sum of the per-word maxima.
    // Two Gaussians per iteration: the second may find the set empty, and then blends the first
    // entry with opacity 0, which changes nothing (alpha 0 is below 1/255). Why: each iteration
    // carries the four runs' state (24 vec4s) through the loop, which lavapipe writes under the
    // loop's execution mask once per iteration; two blends per iteration measured 8 % faster
    // (bench train, blur-only), three the same as two, four slower.
    uint nwords = (n + 31u) / 32u, w = 0u, bits = block_bits[lid][0];
    while (!done) {
      while (bits == 0u && w + 1u < nwords) bits = block_bits[lid][++w];
      if (bits == 0u) break;
      EVF_VISIT(true)
      while (bits == 0u && w + 1u < nwords) bits = block_bits[lid][++w];
      EVF_VISIT(bits != 0u)
      done = true EVF_RUNS(EVF_DONE);
    }
  }
  uint q0 = block_run_vec4(tile, pc.tiles_x, lid);
#define EVF_STORE(i) store_run(r##i, p0 + ivec2(0, i), q0 + 4u * i);
  EVF_RUNS(EVF_STORE)
}
