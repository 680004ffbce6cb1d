#version 450
// Backward rasterization for CPU drivers: one workgroup per 16x16 tile, each invocation owns a
// block of 4 x EVF_ROWS pixels (rows of 4 held as vec4s), as rasterize_block.comp, and visits
// back to front only the Gaussians whose support reaches its block (support_blocks). Per Gaussian
// it sums its block's gradient terms in registers (fixed order; Grad) and stores the 9 sums in
// its own row of the batch's partial sums; once every block is done, each entry's partial sums
// are added in block order and written to its slot. Same maths as rasterize_bwd.comp.
// Why: see rasterize_block.comp; in addition, one set of partial sums per block instead of per
// pixel, and plain stores instead of shared float atomics: lavapipe runs each atomic as a loop of
// locked compare-and-swaps over the lanes, and the nine per visit were a third of this kernel.
// EVF_SUBGROUP_BARRIERS (the "_sg" builds, chosen when the workgroup is one subgroup): the
// workgroup's barriers are subgroup barriers. lavapipe suspends the kernel's coroutine at every
// workgroup barrier (two per batch here), a subgroup barrier it does not: about a tenth of this
// kernel. The "_sg8" build takes blocks of 4 x 8 pixels, a tile in 8 invocations, for 8-lane
// subgroups; the forward's blocks of 4 x 4 are then merged two by two (block_word).
#extension GL_GOOGLE_include_directive : require
#ifdef EVF_SUBGROUP_BARRIERS
#extension GL_KHR_shader_subgroup_basic : require
#define EVF_GROUP_BARRIER() \
  subgroupMemoryBarrierShared(); \
  subgroupBarrier()
#else
#define EVF_GROUP_BARRIER() barrier()
#endif
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
#ifndef EVF_ROWS
#define EVF_ROWS 4
#endif
// 4 rows measured best on lavapipe (bench raster 100k: 2 and 8 rows slower or equal).
// EVF_RUNS(X) expands X(i) for each row i of the block; EVF_QUADS(X) X(k) for each group of four
// rows (block_exp: the forward's groups, so that both take the same exp(power)).
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
// Batches of 32: each block's partial sums of a batch take 36 bytes per entry, 18 KiB for the
// tile's 16 blocks (lavapipe has 32 KiB of shared memory); with atomics into one accumulator,
// batches of 32 to 256 measured alike.
#define EVF_BATCH 32
#if EVF_BLOCKS > 16
#error the partial sums of more than 16 blocks do not fit in 32 KiB of shared memory
#endif
#include "splat/raster_io.glsl"
#include "common/texel.glsl"
// Read as texels, like the Gaussians (raster_io.glsl): each block's start reads 4 x EVF_ROWS
// pixels' state and image gradients, 18 storage accesses a row of 4 that were each a loop over the
// lanes. Tile by tile (splat_layout.h): a run is one texel of InT, four of InLast.
layout(binding = kRasterizeBwdBindInT) uniform samplerBuffer InT;
layout(binding = kRasterizeBwdBindInLast) uniform usamplerBuffer InLast;  // R32UI
layout(binding = kRasterizeBwdBindVRgb) uniform samplerBuffer VRgb;       // [3][H][W] floats
layout(binding = kRasterizeBwdBindVAlpha) uniform samplerBuffer VAlpha;   // [H][W] floats
// Per-slot gradients (splat_layout.h): (v_mean2d.xy, v_conic.xy), (v_conic.z, v_opacity, v_rgb.rg), v_rgb.b.
layout(std430, binding = kRasterizeBwdBindG0) writeonly buffer G0 { vec4 slot_grad_a[]; };
layout(std430, binding = kRasterizeBwdBindG1) writeonly buffer G1 { vec4 slot_grad_b[]; };
layout(std430, binding = kRasterizeBwdBindG2) writeonly buffer G2 { float slot_grad_c[]; };
// Each loaded word's bit sets per block, as the forward found them (splat_layout.h,
// block_word_index), as R32UI texels.
layout(binding = kRasterizeBwdBindInBlocks) uniform usamplerBuffer InBlocks;
uint forward_word(uint word, uint b) { return texelFetch(InBlocks, int(kForwardBlocks * word + b)).x; }
#if EVF_ROWS == 4
uint block_word(uint word, uint b) { return forward_word(word, b); }
#elif EVF_ROWS == 8
// Block (R, c) of 4 x 8 pixels, b = 4 R + c, holds the forward's blocks (2R, c) and (2R + 1, c)
// of 4 x 4: 8 R + c and 8 R + 4 + c.
uint block_word(uint word, uint b) {
  uint f = b + 4u * (b / 4u);
  return forward_word(word, f) | forward_word(word, f + 4u);
}
#else
#error the forward's blocks are 4 x 4: the backward's are 4 x 4 or 4 x 8
#endif
layout(push_constant) uniform PC { RasterPC pc; };

// A batch's partial sums, one row per block: entry e's nine sums in part_a[b][e] = (mean.xy,
// conic.xy), part_b[b][e] = (conic.z, opacity, rgb.rg), part_c[b][e] = rgb.b, the per-slot layout.
// Block b writes only row b, and only the entries it visits; the read-out reads only those.
shared vec4 part_a[EVF_BLOCKS][EVF_BATCH];
shared vec4 part_b[EVF_BLOCKS][EVF_BATCH];
shared float part_c[EVF_BLOCKS][EVF_BATCH];
shared uint block_last[EVF_BLOCKS];  // one past each block's last blended Gaussian

struct Run {     // 4 horizontally adjacent pixels
  vec4 T;                  // transmittance before the current Gaussian
  vec4 Sv;                 // dot(colour of everything behind it, v_rgb)
  vec4 vr, vg, vb, vAT;    // v_rgb, v_alpha * final T
  uvec4 last;              // one past the last blended Gaussian (0 blends nothing)
};

// One Gaussian's gradient terms over a block, summed down its 4 columns of pixels: the rows differ
// only in dy, so the mean and conic gradients need only the sums of v_power times 1, dy and dy^2
// (grad_of then weighs them with dx and the conic once a visit, not once a row).
struct Grad {
  vec4 p, py, pyy;  // v_power, dy v_power, dy^2 v_power
  vec4 r, g, b;     // w v_rgb
  vec4 opac;        // G v_alpha
};

Grad grad_zero() {
  Grad g;
  g.p = g.py = g.pyy = g.r = g.g = g.b = g.opac = vec4(0.0);
  return g;
}

float sum4(vec4 v) { return (v.x + v.y) + (v.z + v.w); }

// The block's nine sums in the per-slot layout: (mean.xy, conic.xy), (conic.z, opacity, rgb.rg),
// rgb.b. power = -(conic.x dx^2 + conic.z dy^2) / 2 - conic.y dx dy, with dx, dy mean - centre.
void grad_of(Grad g, vec4 dx, vec3 conic, out vec4 ga, out vec4 gb, out float gc) {
  float sx = dot(g.p, dx), sxx = dot(g.p, dx * dx);
  float sy = sum4(g.py), sxy = dot(g.py, dx), syy = sum4(g.pyy);
  ga = vec4(-(conic.x * sx + conic.y * sy), -(conic.y * sx + conic.z * sy), -0.5 * sxx, -sxy);
  gb = vec4(-0.5 * syy, sum4(g.opac), sum4(g.r), sum4(g.g));
  gc = sum4(g.b);
}

// `q`: the run's vec4 in the tile-by-tile planes.
Run run_init(ivec2 p0, uint q, uint first) {
  Run r;
  uint hw = pc.width * pc.height;
  vec4 T4 = texelFetch(InT, int(q));
  uvec4 last4 = evf_texel_uvec4(InLast, q);
  for (int k = 0; k < 4; ++k) {
    ivec2 p = p0 + ivec2(k, 0);
    bool inside = p.x < int(pc.width) && p.y < int(pc.height);
    uint i = inside ? uint(p.y) * pc.width + uint(p.x) : 0u;
    float T = inside ? T4[k] : 1.0;
    r.T[k] = T;
    r.last[k] = inside ? last4[k] : first;
    r.vr[k] = inside ? evf_texel_float(VRgb, i) : 0.0;
    r.vg[k] = inside ? evf_texel_float(VRgb, hw + i) : 0.0;
    r.vb[k] = inside ? evf_texel_float(VRgb, 2u * hw + i) : 0.0;
    r.vAT[k] = inside ? evf_texel_float(VAlpha, i) * T : 0.0;
  }
  r.Sv = (pc.background.r * r.vr + pc.background.g * r.vg + pc.background.b * r.vb) * r.T;
  return r;
}

uint run_last(Run r) { return max(max(r.last.x, r.last.y), max(r.last.z, r.last.w)); }

// Gaussian `idx` (already read) against the run at dy = mean.y - its centres' y, with G its
// exp(power) there (block_exp): updates the run's state and adds the run's gradient terms to g
// (zeros where no pixel contributed).
void accumulate(inout Run r, inout Grad g, float dy, vec4 G, float opacity, vec3 col, uint idx) {
  bvec4 live = lessThan(uvec4(idx), r.last);
  vec4 raw = opacity * G;
  vec4 alpha = min(vec4(kAlphaMax), raw);
  bvec4 c = bvec4(uvec4(live) & uvec4(greaterThanEqual(alpha, vec4(kAlphaMin))));
  vec4 inv_one_minus = 1.0 / (1.0 - alpha);  // alpha <= 0.99
  vec4 T_before = r.T * inv_one_minus;
  vec4 w = mix(vec4(0.0), alpha * T_before, c);
  g.r += w * r.vr;
  g.g += w * r.vg;
  g.b += w * r.vb;
  vec4 col_dot_v = col.r * r.vr + col.g * r.vg + col.b * r.vb;
  vec4 v_alpha_j = T_before * col_dot_v + (r.vAT - r.Sv) * inv_one_minus;
  r.Sv += w * col_dot_v;  // only S . v_rgb is ever needed
  r.T = mix(r.T, T_before, c);
  bvec4 smooth_part = bvec4(uvec4(c) & uvec4(lessThan(raw, vec4(kAlphaMax))));
  vec4 v_power = mix(vec4(0.0), alpha * v_alpha_j, smooth_part);
  g.p += v_power;
  g.py += dy * v_power;
  g.pyy += (dy * dy) * v_power;
  g.opac += mix(vec4(0.0), G * v_alpha_j, smooth_part);
}

void main() {
  ivec2 tile = tile_of_group(pc.tiles_x);
  uint lid = gl_LocalInvocationIndex;
  ivec2 p0 = tile * int(kTileSize) + ivec2(int(lid % 4u) * 4, int(lid / 4u) * EVF_ROWS);
  float cxm = float(p0.x) + 2.0;  // the middle of the block's columns
  vec4 cx = vec4(p0.x) + vec4(0.5, 1.5, 2.5, 3.5);
  float cy = float(p0.y) + 0.5;
  uint tile_index = uint(tile.y) * pc.tiles_x + uint(tile.x);
  uvec2 range = tile_range[tile_index];
  uint last = range.x;
  uint q0 = block_run_vec4(tile, pc.tiles_x, lid);
#define EVF_INIT(i) Run r##i = run_init(p0 + ivec2(0, i), q0 + 4u * i, range.x); last = max(last, run_last(r##i));
  EVF_RUNS(EVF_INIT)
#define EVF_EXP(k) block_exp(conic, dxm, a.y - (cy + (4.0 * k + 1.5)), G[4 * k], G[4 * k + 1], G[4 * k + 2], G[4 * k + 3]);
#define EVF_ACC(i) accumulate(r##i, g, a.y - (cy + float(i)), G[i], b.y, col, start + j);
  uint count = range.y - range.x;
  // Every invocation keeps every block's `last` in registers, for the read-out. Gaussians at or
  // past the largest (visit_end) blended into no pixel: neither loaded nor visited, their slots
  // keep the zeros the host filled the gradient planes with.
  block_last[lid] = last;
  EVF_GROUP_BARRIER();
  uint lasts[EVF_BLOCKS], visit_end = range.x;
  for (uint b = 0u; b < EVF_BLOCKS; ++b) {
    lasts[b] = block_last[b];
    visit_end = max(visit_end, lasts[b]);
  }
  for (uint nb = (count + EVF_BATCH - 1u) / EVF_BATCH; nb > 0u; --nb) {
    uint start = range.x + (nb - 1u) * EVF_BATCH;
    uint n = min(uint(EVF_BATCH), range.y - start);
    // Entries at or past visit_end are neither loaded nor visited nor written.
    uint n_load = start < visit_end ? min(n, visit_end - start) : 0u;
    uint n_visit = start < last ? min(n, last - start) : 0u;  // n_visit <= n_load
    EVF_GROUP_BARRIER();  // the previous batch's read-out is done with the partial sums
    // This block's entries below its last blended one. A word with an entry below visit_end was
    // loaded by the forward, which kept its bit sets; another one's (n_load 0) may hold anything,
    // and nothing of it is used: no bit survives the masks, the read-out runs no trip.
    uint word = block_word_index(start, tile_index);
    uint bits = block_word(word, lid);
    if (n_visit < 32u) bits &= (1u << n_visit) - 1u;
    // Back to front.
    while (bits != 0u) {
      uint j = uint(findMSB(bits));
      bits &= ~(1u << j);
      uint gid = gaussian_of_isect(start + j);
      vec4 a = proj_a(gid), b = proj_b(gid);
      vec3 conic = vec3(a.zw, b.x), col = proj_c(gid).rgb;
      vec4 dx = a.x - cx;
      float dxm = a.x - cxm;
      vec4 G[EVF_ROWS];
      EVF_QUADS(EVF_EXP)
      Grad g = grad_zero();
      EVF_RUNS(EVF_ACC)
      vec4 ga, gb;
      float gc;
      grad_of(g, dx, conic, ga, gb, gc);
      part_a[lid][j] = ga;
      part_b[lid][j] = gb;
      part_c[lid][j] = gc;
    }
    EVF_GROUP_BARRIER();
    // Each block's bit set, for the blocks that visited each entry.
    uint words[EVF_BLOCKS];
    for (uint b = 0u; b < EVF_BLOCKS; ++b) words[b] = block_word(word, b);
    for (uint k = lid; k < n_load; k += EVF_THREADS) {
      uint visited = 0u;  // the blocks that visited entry k
      for (uint b = 0u; b < EVF_BLOCKS; ++b) visited |= uint(start + k < lasts[b]) * ((words[b] >> k) & 1u) << b;
      vec4 sa = vec4(0.0), sb = vec4(0.0);
      float sc = 0.0;
      while (visited != 0u) {
        uint b = uint(findLSB(visited));
        visited &= visited - 1u;
        sa += part_a[b][k];
        sb += part_b[b][k];
        sc += part_c[b][k];
      }
      uint slot = slot_of_isect(start + k);
      slot_grad_a[slot] = sa;
      slot_grad_b[slot] = sb;
      slot_grad_c[slot] = sc;
    }
  }
}
