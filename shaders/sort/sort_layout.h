// Stable LSD radix sort of (uint key, uint value) pairs, 4 bits per pass: layouts shared by
// engine/sort and shaders/sort.
#ifndef EVF_SORT_LAYOUT_H
#define EVF_SORT_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kSortGroupSize, 256u)
EVF_CONST(uint, kSortItems, 16u)          // consecutive elements per invocation
EVF_CONST(uint, kSortBlock, 4096u)        // kSortGroupSize * kSortItems
EVF_CONST(uint, kSortBins, 16u)           // 4-bit digits
struct SortPC {
  uint n;           // number of pairs
  uint shift;       // bit offset of this pass's digit
  uint num_blocks;  // ceil(n / kSortBlock)
  uint pad;
};
EVF_NAMESPACE_END
#endif
