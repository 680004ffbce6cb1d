// Exclusive prefix sum of uint arrays: layouts shared by engine/scan and shaders/scan.
#ifndef EVF_SCAN_LAYOUT_H
#define EVF_SCAN_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kScanGroupSize, 256u)
// 16 consecutive elements per invocation: the in-workgroup scan of the 256 partial sums is a fixed
// cost per invocation (on CPU drivers 8 steps of lane-looped shared accesses), spread over 16.
EVF_CONST(uint, kScanItems, 16u)
EVF_CONST(uint, kScanBlock, 4096u)  // kScanGroupSize * kScanItems
// The "_wide" builds (CPU drivers): the same blocks as 16 invocations of 256 elements, read and
// written four at a time; a workgroup of 256 on lavapipe is 32 SIMD vectors switched at each of
// its 8 barriers, and one of 16 scans a block about 0.1 ms faster.
EVF_CONST(uint, kScanGroupSizeWide, 16u)
EVF_CONST(uint, kScanItemsWide, 256u)  // kScanGroupSizeWide * kScanItemsWide = kScanBlock
// Up to this many elements the wide scan is one dispatch of one workgroup ("_wide_single"):
// 64k elements, about 0.1 ms of work on lavapipe, where two more dispatches cost about 0.2.
EVF_CONST(uint, kScanSingleMax, 65536u)
struct ScanPC {
  uint n_out;   // elements written: out[i] = sum(in[0..i)) for i < n_out
  uint n_in;    // elements read: in[i] for i < n_in, zero beyond
  uint pad0, pad1;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// scan/scan_add
EVF_BIND(kScanAddBindValues, 0u, Values)
EVF_BIND(kScanAddBindOffsets, 1u, Offsets)
// scan/scan_block
EVF_BIND(kScanBlockBindIn, 0u, In)
EVF_BIND(kScanBlockBindOut, 1u, Out)
EVF_BIND(kScanBlockBindSums, 2u, Sums)

EVF_NAMESPACE_END
#endif
