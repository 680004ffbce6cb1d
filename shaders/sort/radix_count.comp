#version 450
// Radix sort pass, step 1: digit histogram of one block of 256 x pc.items keys.
// One invocation reads pc.items consecutive keys (four per access where it can: CPU drivers loop
// over the lanes for every access); counts meet in shared memory; the histogram is
// written digit-major (counts[digit * num_blocks + block]) so one exclusive scan over it gives
// every (digit, block) its global output offset.
#extension GL_GOOGLE_include_directive : require
#include "sort/sort_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kSortGroupSize) in;
layout(std430, binding = kRadixCountBindKeys) readonly buffer Keys { uvec4 keys[]; };  // 4 keys per access
layout(std430, binding = kRadixCountBindCounts) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform PC { SortPC pc; };
shared uint hist[16];

void main() {
  uint block = evf_linear_group();
  uint lid = gl_LocalInvocationIndex;
  if (lid < 16) hist[lid] = 0;
  barrier();
  uint local[16];
  for (uint d = 0; d < 16; ++d) local[d] = 0;
  uint base = block * kSortGroupSize * pc.items + lid * pc.items;
  uint end = min(base + pc.items, pc.n), i = base;
  if ((pc.items & 3u) == 0u)  // base is a multiple of 4: whole uvec4s while 4 keys remain
    for (; i + 4u <= end; i += 4u) {
      uvec4 d = (keys[i >> 2u] >> pc.shift) & 15u;
      local[d.x] += 1;
      local[d.y] += 1;
      local[d.z] += 1;
      local[d.w] += 1;
    }
  for (; i < end; ++i) local[(keys[i >> 2u][i & 3u] >> pc.shift) & 15u] += 1;
  for (uint d = 0; d < 16; ++d)
    if (local[d] != 0) atomicAdd(hist[d], local[d]);
  barrier();
  if (lid < 16) counts[lid * pc.num_blocks + block] = hist[lid];
}
