#version 450
// Radix sort pass, step 2: stable scatter of one block of EVF_SORT_GROUP x pc.items pairs.
// One invocation owns pc.items consecutive pairs. Its per-digit counts go to shared memory as a
// [digit][invocation] table; an exclusive scan of that table (digit-major) gives each
// invocation, for each digit, how many earlier pairs of the block share that digit. The
// invocation then writes its pairs in order, so equal digits keep their input order (stable).
// Uses shared memory only: correct for any subgroup size.
// EVF_SORT_FUSED_SCAN (the "_fused" builds, CPU drivers with few blocks): the counts are the count
// pass's raw histograms, and each workgroup sums what it needs of them itself (every digit's
// total, and its own digit's counts in the blocks before it), so that no scan runs between the
// two passes (on lavapipe a dispatch of its own, which costs more than this).
#extension GL_GOOGLE_include_directive : require
#include "sort/sort_layout.h"
#include "sort/sort_build.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = EVF_SORT_GROUP) in;
// Read four pairs per access where it can (CPU drivers loop over the lanes for every storage
// access). The wide builds (CPU drivers) read keys, values and counts as R32UI texels instead:
// on lavapipe straight-line code, not a loop over the lanes.
#ifdef EVF_SORT_WIDE
#include "common/texel.glsl"
layout(binding = kRadixScatterBindKeysIn) uniform usamplerBuffer KeysIn;
uvec4 key4_in(uint i) { return evf_texel_uvec4(KeysIn, i >> 2u); }
uint key_in(uint i) { return texelFetch(KeysIn, int(i)).x; }
#else
layout(std430, binding = kRadixScatterBindKeysIn) readonly buffer KeysIn { uvec4 keys_in[]; };
uvec4 key4_in(uint i) { return keys_in[i >> 2u]; }
uint key_in(uint i) { return keys_in[i >> 2u][i & 3u]; }
#endif
#ifdef EVF_SORT_ORDER
// The "_order" builds (a first pass that makes the sort's permutation): each pair's value is its
// key's index, computed instead of read, so that nobody writes or reads an identity array.
uvec4 value4_in(uint i) { return uvec4(i) + uvec4(0u, 1u, 2u, 3u); }
uint value_in(uint i) { return i; }
#elif defined(EVF_SORT_WIDE)
layout(binding = kRadixScatterBindValuesIn) uniform usamplerBuffer ValuesIn;
uvec4 value4_in(uint i) { return evf_texel_uvec4(ValuesIn, i >> 2u); }
uint value_in(uint i) { return texelFetch(ValuesIn, int(i)).x; }
#else
layout(std430, binding = kRadixScatterBindValuesIn) readonly buffer ValuesIn { uvec4 values_in[]; };
uvec4 value4_in(uint i) { return values_in[i >> 2u]; }
uint value_in(uint i) { return values_in[i >> 2u][i & 3u]; }
#endif
layout(std430, binding = kRadixScatterBindKeysOut) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = kRadixScatterBindValuesOut) writeonly buffer ValuesOut { uint values_out[]; };
// Scanned counts, or with EVF_SORT_FUSED_SCAN the raw ones (both digit-major: [digit][block]).
#ifdef EVF_SORT_WIDE
layout(binding = kRadixScatterBindOffsets) uniform usamplerBuffer Offsets;
uint offset_at(uint i) { return texelFetch(Offsets, int(i)).x; }
#else
layout(std430, binding = kRadixScatterBindOffsets) readonly buffer Offsets { uint global_offset[]; };
uint offset_at(uint i) { return global_offset[i]; }
#endif
layout(push_constant) uniform PC { SortPC pc; };

shared uint table[EVF_SORT_BINS * EVF_SORT_GROUP];   // [digit][invocation], then its exclusive scan
// Per invocation, the sum of its row of the table (x) and, fused, of its digits' totals (y).
shared uvec2 partial[2][EVF_SORT_GROUP];
#ifdef EVF_SORT_FUSED_SCAN
shared uint digit_base[EVF_SORT_BINS];  // where this block's keys of each digit start
// The digits of one row of the table (the wide build: 256 digits, 16 invocations).
const uint kDigitsPerRow = EVF_SORT_BINS / EVF_SORT_GROUP;
#endif

void main() {
  uint block = evf_linear_group();
  uint lid = gl_LocalInvocationIndex;
  uint base = block * EVF_SORT_GROUP * pc.items + lid * pc.items;
  uint end = min(base + pc.items, pc.n);
  // Whole uvec4s from base to end4 (base is a multiple of 4 when items is), single pairs after.
  uint end4 = (pc.items & 3u) == 0u && end > base ? base + ((end - base) & ~3u) : base;
  uint local[EVF_SORT_BINS];
  for (uint d = 0; d < EVF_SORT_BINS; ++d) local[d] = 0;
  for (uint i = base; i < end4; i += 4u) {
    uvec4 d = (key4_in(i) >> pc.shift) & pc.digit_mask;
    local[d.x] += 1;
    local[d.y] += 1;
    local[d.z] += 1;
    local[d.w] += 1;
  }
  for (uint i = end4; i < end; ++i) local[(key_in(i) >> pc.shift) & pc.digit_mask] += 1;
  for (uint d = 0; d < EVF_SORT_BINS; ++d) table[d * EVF_SORT_GROUP + lid] = local[d];
  barrier();
  // Scan of the table: invocation lid sums entries [lid * BINS, lid * BINS + BINS) (with 256
  // digits in 16 invocations, the rows of digits [16 lid, 16 lid + 16)).
  uvec2 sum = uvec2(0u);
  for (uint k = 0; k < EVF_SORT_BINS; ++k) sum.x += table[lid * EVF_SORT_BINS + k];
#ifdef EVF_SORT_FUSED_SCAN
  // The same digits' totals over all blocks, and their counts in the blocks before this one.
  uint before[kDigitsPerRow], total[kDigitsPerRow];
  for (uint k = 0; k < kDigitsPerRow; ++k) {
    uint row = (lid * kDigitsPerRow + k) * pc.num_blocks;
    before[k] = total[k] = 0u;
    for (uint b = 0u; b < pc.num_blocks; ++b) {
      uint c = offset_at(row + b);
      before[k] += b < block ? c : 0u;
      total[k] += c;
    }
    sum.y += total[k];
  }
#endif
  partial[0][lid] = sum;
  barrier();
  uint src = 0;
  for (uint off = 1; off < EVF_SORT_GROUP; off <<= 1) {
    uvec2 x = partial[src][lid];
    if (lid >= off) x += partial[src][lid - off];
    partial[1 - src][lid] = x;
    src = 1 - src;
    barrier();
  }
  uvec2 first = partial[src][lid] - sum;  // exclusive prefixes
  uint run = first.x;
  for (uint k = 0; k < EVF_SORT_BINS; ++k) {
    uint v = table[lid * EVF_SORT_BINS + k];
    table[lid * EVF_SORT_BINS + k] = run;
    run += v;
  }
#ifdef EVF_SORT_FUSED_SCAN
  uint below = first.y;  // keys of all digits below this invocation's first
  for (uint k = 0; k < kDigitsPerRow; ++k) {
    digit_base[lid * kDigitsPerRow + k] = below + before[k];
    below += total[k];
  }
#define EVF_BLOCK_DIGIT_BASE(d) digit_base[d]
#else
#define EVF_BLOCK_DIGIT_BASE(d) offset_at((d) * pc.num_blocks + block)
#endif
  barrier();
  // Position of pair: offset of (digit, block) + rank among the block's pairs of that digit.
  uint dest[EVF_SORT_BINS];
  for (uint d = 0; d < EVF_SORT_BINS; ++d)
    dest[d] = EVF_BLOCK_DIGIT_BASE(d) + table[d * EVF_SORT_GROUP + lid] - table[d * EVF_SORT_GROUP];
  for (uint i = base; i < end4; i += 4u) {
    uvec4 key = key4_in(i), value = value4_in(i);
    for (uint c = 0u; c < 4u; ++c) {
      uint d = (key[c] >> pc.shift) & pc.digit_mask;
      uint o = dest[d];
      dest[d] = o + 1;
      keys_out[o] = key[c];
      values_out[o] = value[c];
    }
  }
  for (uint i = end4; i < end; ++i) {
    uint key = key_in(i);
    uint d = (key >> pc.shift) & pc.digit_mask;
    uint o = dest[d];
    dest[d] = o + 1;
    keys_out[o] = key;
    values_out[o] = value_in(i);
  }
}
