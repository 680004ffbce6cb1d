#version 450
// Exact depth order within equal sort keys. The sort's keys hold each depth's top depth_bits bits
// (emit.comp), so Gaussians of one tile whose depths share them come out in Gaussian order; this
// pass puts every such run of equal keys in the order of the depths themselves (an insertion
// sort, stable: equal depths stay in Gaussian order), so that each tile's list is in exact depth
// order whatever the key's width. Runs never cross tiles (the key starts with the tile).
// One invocation per kDepthRunsSpan sorted positions, their keys and their neighbours' read in
// straight-line code (on lavapipe a kernel's cost is mostly per invocation and per loop trip):
// the first position of each run of two or more sorts it. With keys of 15 depth bits or more,
// most runs are a single entry, and depths that share a key by chance come mostly in pairs.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kDepthRunsGroupSize) in;
#ifdef EVF_DEPTH_RUNS_TEXELS
// The "_block" build (CPU drivers) reads the keys, slots' Gaussians and depths as texels (why:
// common/texel.glsl); the slots it sorts in place stay a storage buffer.
layout(binding = kDepthRunsBindKeys) uniform usamplerBuffer Keys;
layout(binding = kDepthRunsBindGid) uniform usamplerBuffer Gid;
layout(binding = kDepthRunsBindProjB) uniform samplerBuffer ProjB;
layout(binding = kDepthRunsBindSlotsIn) uniform usamplerBuffer SlotsIn;
uint key_at(uint i) { return texelFetch(Keys, int(i)).x; }
float depth_of_slot(uint s) { return texelFetch(ProjB, int(texelFetch(Gid, int(s)).x)).z; }
// Before this invocation writes them (no other touches its runs): the sorted slots as texels.
uint slot_before(uint i) { return texelFetch(SlotsIn, int(i)).x; }
#else
layout(std430, binding = kDepthRunsBindKeys) readonly buffer Keys { uint keys[]; };
layout(std430, binding = kDepthRunsBindGid) readonly buffer Gid { uint gaussian_id_from_slot[]; };
layout(std430, binding = kDepthRunsBindProjB) readonly buffer ProjB { vec4 proj_misc[]; };  // .z: depth
uint key_at(uint i) { return keys[i]; }
float depth_of_slot(uint s) { return proj_misc[gaussian_id_from_slot[s]].z; }
#endif
layout(std430, binding = kDepthRunsBindSlots) buffer Slots { uint sorted_slots[]; };
#ifndef EVF_DEPTH_RUNS_TEXELS
uint slot_before(uint i) { return sorted_slots[i]; }
#endif
layout(push_constant) uniform PC { RasterPC pc; };

// Sorted positions [j, e) by the depth of their slots' Gaussians, stably. A pair (most runs) is
// swapped or left alone; longer runs take an insertion sort in place.
void sort_run(uint j, uint e) {
  if (e == j + 2u) {
    uint s0 = slot_before(j), s1 = slot_before(j + 1u);
    if (depth_of_slot(s1) < depth_of_slot(s0)) {
      sorted_slots[j] = s1;
      sorted_slots[j + 1u] = s0;
    }
    return;
  }
  for (uint i = j + 1u; i < e; ++i) {
    uint s = sorted_slots[i];
    float d = depth_of_slot(s);
    uint p = i;
    while (p > j && depth_of_slot(sorted_slots[p - 1u]) > d) {
      sorted_slots[p] = sorted_slots[p - 1u];
      --p;
    }
    sorted_slots[p] = s;
  }
}

void main() {
  uint i0 = evf_linear_invocation(kDepthRunsGroupSize) * kDepthRunsSpan;
  if (i0 + 1u >= pc.num_isects) return;  // the last position starts no run of two
  uint last = pc.num_isects - 1u, tiles = pc.tiles_x * pc.tiles_y;
  // keys of positions i0 - 1 .. i0 + kDepthRunsSpan (clamped to the list; clamped copies compare
  // equal only where the real neighbour would not count: see `starts`).
  uint key[kDepthRunsSpan + 2u];
  [[unroll]] for (uint k = 0u; k < kDepthRunsSpan + 2u; ++k) key[k] = key_at(clamp(i0 + k, 1u, last + 1u) - 1u);
  // Bit k: position i0 + k starts a run of two or more of a tile's keys.
  uint starts = 0u;
  [[unroll]] for (uint k = 0u; k < kDepthRunsSpan; ++k) {
    uint i = i0 + k;
    bool first = (i == 0u || key[k] != key[k + 1u]) && i < last && key[k + 2u] == key[k + 1u];
    starts |= uint(first && (key[k + 1u] >> pc.depth_bits) < tiles) << k;
  }
  while (starts != 0u) {
    uint i = i0 + uint(findLSB(starts));
    starts &= starts - 1u;
    uint k = key_at(i), e = i + 2u;
    while (e < pc.num_isects && key_at(e) == k) ++e;
    sort_run(i, e);
  }
}
