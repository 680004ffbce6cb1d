// Stable LSD radix sort of (uint key, uint value) pairs: layouts shared by engine/sort and
// shaders/sort. Two builds of the same kernels: 4-bit digits in workgroups of 256 (GPUs), and
// 8-bit digits in workgroups of 16 ("_wide", CPU drivers: half the passes over the keys; the
// per-invocation tables of 256 counts fit the shared memory only in a small workgroup).
#ifndef EVF_SORT_LAYOUT_H
#define EVF_SORT_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kSortGroupSize, 256u)
EVF_CONST(uint, kSortBins, 16u)  // 4-bit digits
EVF_CONST(uint, kSortGroupSizeWide, 16u)
EVF_CONST(uint, kSortBinsWide, 256u)  // 8-bit digits
// Consecutive elements per invocation (SortPC.items): GPUs 16 (more workgroups in flight), CPU
// drivers up to 4096 in the wide build (the per-invocation work over the 256 digits, a fixed cost,
// is spread over more keys; RadixSort sizes the blocks to whole rounds of the CPU threads).
EVF_CONST(uint, kSortItemsGpu, 16u)
EVF_CONST(uint, kSortItemsCpu, 4096u)
EVF_CONST(uint, kSortItemsMax, 4096u)
// Up to this many blocks the wide scatter scans the count pass's histograms itself ("_fused"
// builds: every workgroup reads all of them, 16 x blocks per invocation); beyond, a scan runs
// between the two passes.
EVF_CONST(uint, kSortFusedBlocksMax, 64u)
struct SortPC {
  uint n;           // number of pairs
  uint shift;       // bit offset of this pass's digit
  uint num_blocks;  // ceil(n / (group size * items))
  uint items;       // consecutive elements per invocation
  uint digit_mask;  // the digit's bits: (key >> shift) & digit_mask (the last pass may be narrower)
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
