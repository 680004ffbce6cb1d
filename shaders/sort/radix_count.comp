#version 450
// Radix sort pass, step 1: digit histogram of one block of EVF_SORT_GROUP x pc.items keys.
// One invocation reads pc.items consecutive keys (four per access where it can: CPU drivers loop
// over the lanes for every access); counts meet in shared memory; the histogram is
// written digit-major (counts[digit * num_blocks + block]) so one exclusive scan over it gives
// every (digit, block) its global output offset.
#extension GL_GOOGLE_include_directive : require
#include "sort/sort_layout.h"
#include "sort/sort_build.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = EVF_SORT_GROUP) in;
#ifdef EVF_SORT_WIDE
// The wide build (CPU drivers) reads the keys as R32UI texels: straight-line code on lavapipe,
// where a storage access is a loop over the lanes.
#include "common/texel.glsl"
layout(binding = kRadixCountBindKeys) uniform usamplerBuffer Keys;
uvec4 key4(uint i) { return evf_texel_uvec4(Keys, i >> 2u); }
uint key1(uint i) { return texelFetch(Keys, int(i)).x; }
#else
layout(std430, binding = kRadixCountBindKeys) readonly buffer Keys { uvec4 keys[]; };  // 4 keys per access
uvec4 key4(uint i) { return keys[i >> 2u]; }
uint key1(uint i) { return keys[i >> 2u][i & 3u]; }
#endif
layout(std430, binding = kRadixCountBindCounts) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform PC { SortPC pc; };
shared uint hist[EVF_SORT_BINS];

void main() {
  uint block = evf_linear_group();
  uint lid = gl_LocalInvocationIndex;
  for (uint d = lid; d < EVF_SORT_BINS; d += EVF_SORT_GROUP) hist[d] = 0;
  barrier();
  uint local[EVF_SORT_BINS];
  for (uint d = 0; d < EVF_SORT_BINS; ++d) local[d] = 0;
  uint base = block * EVF_SORT_GROUP * pc.items + lid * pc.items;
  uint end = min(base + pc.items, pc.n), i = base;
  if ((pc.items & 3u) == 0u)  // base is a multiple of 4: whole uvec4s while 4 keys remain
    for (; i + 4u <= end; i += 4u) {
      uvec4 d = (key4(i) >> pc.shift) & pc.digit_mask;
      local[d.x] += 1;
      local[d.y] += 1;
      local[d.z] += 1;
      local[d.w] += 1;
    }
  for (; i < end; ++i) local[(key1(i) >> pc.shift) & pc.digit_mask] += 1;
  for (uint d = 0; d < EVF_SORT_BINS; ++d)
    if (local[d] != 0) atomicAdd(hist[d], local[d]);
  barrier();
  for (uint d = lid; d < EVF_SORT_BINS; d += EVF_SORT_GROUP) counts[d * pc.num_blocks + block] = hist[d];
}
