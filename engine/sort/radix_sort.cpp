#include "sort/radix_sort.h"

#include <algorithm>

#include "sort/sort_layout.h"

namespace evflow {

using namespace shaderio;

RadixSort::RadixSort(gpu::Context& ctx)
    : ctx_(ctx),
      scan_(ctx),
      keys_tmp_(ctx, 16, "sort_keys_tmp"),
      values_tmp_(ctx, 16, "sort_values_tmp"),
      counts_(ctx, 16, "sort_counts"),
      items_(ctx.options().sort_items) {}

void RadixSort::set_items(uint32_t items) { items_ = items ? std::clamp<uint32_t>(items, 1u, 256u) : 0u; }

uint32_t RadixSort::items_for(uint32_t n) const {
  if (items_) return items_;
  uint32_t items = ctx_.caps().cpu_driver ? kSortItemsCpu : kSortItemsGpu;
  // Short inputs: smaller blocks so that at least two workgroups share the work (a single block
  // runs on one CPU thread). More than two made medium sizes slower (bench train's sort).
  while (items > kSortItemsGpu && uint64_t(n) < uint64_t(2) * kSortGroupSize * items) items /= 2;
  return items;
}

void RadixSort::reserve(uint32_t n) {
  if (n <= 1) return;
  const uint32_t n_counts = gpu::Commands::div_up(n, kSortGroupSize * items_for(n)) * kSortBins;
  counts_.ensure(uint64_t(n_counts + 1) * 4);
  scan_.reserve(n_counts);
}

std::pair<const gpu::Buffer*, const gpu::Buffer*> RadixSort::record(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                    const gpu::Buffer& values, uint32_t n,
                                                                    uint32_t bits) {
  return record(cmd, keys, values, keys_tmp_, values_tmp_, n, bits);
}

std::pair<const gpu::Buffer*, const gpu::Buffer*> RadixSort::record(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                    const gpu::Buffer& values, gpu::Buffer& keys_alt,
                                                                    gpu::Buffer& values_alt, uint32_t n,
                                                                    uint32_t bits) {
  if (n <= 1 || bits == 0) return {&keys, &values};
  keys_alt.ensure(uint64_t(n) * 4);
  values_alt.ensure(uint64_t(n) * 4);
  const uint32_t items = items_for(n);
  const uint32_t blocks = gpu::Commands::div_up(n, kSortGroupSize * items);
  const uint32_t n_counts = blocks * kSortBins;
  reserve(n);
  const gpu::Buffer* kin = &keys;
  const gpu::Buffer* vin = &values;
  const gpu::Buffer* kout = &keys_alt;
  const gpu::Buffer* vout = &values_alt;
  for (uint32_t shift = 0; shift < bits; shift += 4) {
    SortPC pc{n, shift, blocks, items};
    cmd.dispatch("sort/radix_count", {{kRadixCountBindKeys, *kin}, {kRadixCountBindCounts, counts_}}, pc,
                 cmd.linear_groups(blocks));
    scan_.record(cmd, counts_, counts_, n_counts, n_counts);
    cmd.dispatch("sort/radix_scatter",
                 {{kRadixScatterBindKeysIn, *kin},
                  {kRadixScatterBindValuesIn, *vin},
                  {kRadixScatterBindKeysOut, *kout},
                  {kRadixScatterBindValuesOut, *vout},
                  {kRadixScatterBindOffsets, counts_}},
                 pc, cmd.linear_groups(blocks));
    std::swap(kin, kout);
    std::swap(vin, vout);
  }
  return {kin, vin};
}

}  // namespace evflow
