// Events on the GPU: the packed event format and the push constants shared by engine/events
// (C++) and shaders/events (GLSL).
//
// One uint per event: x in bits 0..14, y in bits 15..29, bit 30 set for positive polarity.
// Times stay on the host (sorted, per training view): the host turns a time window into an
// index range by binary search, so kernels only see [first, first + count).
#ifndef EVF_EVENTS_LAYOUT_H
#define EVF_EVENTS_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kEventGroupSize, 256u)
EVF_CONST(uint, kEventCoordBits, 15u)
EVF_CONST(uint, kEventCoordMask, 0x7FFFu)
EVF_CONST(uint, kEventPositiveBit, 0x40000000u)
EVF_CONST(uint, kEventMaxCoord, 32767u)

// events/accumulate: for each event e in [first, first + count):
//   counts[plane * 2 * H * W + (p > 0 ? 0 : H * W) + y * W + x] += 1   (integer atomics: exact,
// order-independent). Plane layout: [positive counts H*W][negative counts H*W] per plane.
struct EventAccumulatePC {
  uint first;
  uint count;
  uint width;
  uint height;
  uint plane;
  uint pad0, pad1, pad2;
};

// events/binned_accumulate: one bin of pre-binned signed counts (binned[offset + p], pixel p =
// y * W + x) weighted by the covered fraction `weight`, added to a float plane:
//   counts[plane * 2 * H * W + p] += weight * max(c, 0),  counts[... + H * W + p] += weight * max(-c, 0)
// (one invocation per pixel; the planes hold the 32 bits of floats).
struct BinnedAccumulatePC {
  uint offset;
  uint width;
  uint height;
  uint plane;
  float weight;
  uint pad0, pad1, pad2;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// events/accumulate
EVF_BIND(kEventAccumulateBindPacked, 0u, Packed)
EVF_BIND(kEventAccumulateBindCounts, 1u, Counts)
// events/binned_accumulate
EVF_BIND(kBinnedAccumulateBindBinned, 0u, Binned)
EVF_BIND(kBinnedAccumulateBindCounts, 1u, Counts)

EVF_NAMESPACE_END
#endif
