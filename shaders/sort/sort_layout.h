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
EVF_NAMESPACE_END
#endif
