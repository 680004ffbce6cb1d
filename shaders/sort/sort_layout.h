// Stable LSD radix sort of (uint key, uint value) pairs, 4 bits per pass: layouts shared by
// engine/sort and shaders/sort.
#ifndef EVF_SORT_LAYOUT_H
#define EVF_SORT_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kSortGroupSize, 256u)
// Consecutive elements per invocation (SortPC.items): GPUs 16 (more workgroups in flight), CPU
// drivers 128 (the per-block ranking work, a fixed cost per invocation, is spread over more keys).
EVF_CONST(uint, kSortItemsGpu, 16u)
EVF_CONST(uint, kSortItemsCpu, 128u)
EVF_CONST(uint, kSortBins, 16u)           // 4-bit digits
struct SortPC {
  uint n;           // number of pairs
  uint shift;       // bit offset of this pass's digit
  uint num_blocks;  // ceil(n / (kSortGroupSize * items))
  uint items;       // consecutive elements per invocation
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// sort/radix_count
EVF_BIND(kRadixCountBindKeys, 0u, Keys)
EVF_BIND(kRadixCountBindCounts, 1u, Counts)
// sort/radix_scatter
EVF_BIND(kRadixScatterBindKeysIn, 0u, KeysIn)
EVF_BIND(kRadixScatterBindValuesIn, 1u, ValuesIn)
EVF_BIND(kRadixScatterBindKeysOut, 2u, KeysOut)
EVF_BIND(kRadixScatterBindValuesOut, 3u, ValuesOut)
EVF_BIND(kRadixScatterBindOffsets, 4u, Offsets)

EVF_NAMESPACE_END
#endif
