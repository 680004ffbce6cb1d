// Stable LSD radix sort of (key, value) uint pairs on the GPU, sorting only the low `bits` bits of
// the keys (bits above are ignored): 4 bits per pass on GPUs, 8 on CPU drivers (sort_layout.h).
// Ping-pongs between the caller's buffers and internal ones; the result is in the buffers
// returned by record().
#pragma once
#include <utility>

#include "gpu/commands.h"
#include "scan/prefix_sum.h"

namespace evflow {

class RadixSort {
 public:
  explicit RadixSort(gpu::Context& ctx);
  // Keys per invocation, 1..kSortItemsMax, for every record from now on; 0 = the device's choice
  // by input size (the default, unless the context's options set sort_items).
  void set_items(uint32_t items);
  // Digit width, 4 or 8, for every record from now on; 0 = the device's choice (8 on CPU drivers).
  void set_digit_bits(uint32_t bits);
  // Records the passes; returns the buffers holding the sorted keys and values (either the
  // inputs or the internal scratch buffers, depending on the pass count).
  std::pair<const gpu::Buffer*, const gpu::Buffer*> record(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                           const gpu::Buffer& values, uint32_t n, uint32_t bits);
  // The same, ping-ponging with the caller's buffers keys_alt / values_alt (grown to n values)
  // instead of internal ones: the result then lives in buffers the caller owns.
  std::pair<const gpu::Buffer*, const gpu::Buffer*> record(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                           const gpu::Buffer& values, gpu::Buffer& keys_alt,
                                                           gpu::Buffer& values_alt, uint32_t n, uint32_t bits);
  // Sorts the keys and makes their sorting permutation in the values: value i = the input index
  // of the i-th key in sorted order (stable), never read from `order` (the first pass computes
  // the indices). Ping-pongs with the caller's buffers as above, each grown to n values.
  std::pair<const gpu::Buffer*, const gpu::Buffer*> record_order(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                 gpu::Buffer& order, gpu::Buffer& keys_alt,
                                                                 gpu::Buffer& order_alt, uint32_t n, uint32_t bits);
  // Grows the internal scratch for sorts of n keys. Recording several sorts into one command
  // buffer must reserve for each size first: a buffer grown while recording would free one the
  // earlier sorts' commands still use.
  void reserve(uint32_t n);

 private:
  // The passes of both records; `order`: the first pass takes the keys' indices as values.
  std::pair<const gpu::Buffer*, const gpu::Buffer*> record_passes(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                  const gpu::Buffer& values, gpu::Buffer& keys_alt,
                                                                  gpu::Buffer& values_alt, uint32_t n, uint32_t bits,
                                                                  bool order);
  uint32_t items_for(uint32_t n) const;
  uint32_t group_size() const;
  uint32_t bins() const;
  gpu::Context& ctx_;
  PrefixSum scan_;
  gpu::Buffer keys_tmp_, values_tmp_, counts_;
  uint32_t items_ = 0;
  bool wide_ = false;     // 8-bit digits
  uint32_t threads_ = 1;  // CPU threads (items_for on CPU drivers)
};

}  // namespace evflow
