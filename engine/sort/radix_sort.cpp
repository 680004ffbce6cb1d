#include "sort/radix_sort.h"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

#include "sort/sort_layout.h"

namespace evflow {

using namespace shaderio;

// The CPU threads a CPU driver runs workgroups on: lavapipe's LP_NUM_THREADS, else one per core.
static uint32_t cpu_threads() {
  if (const char* v = std::getenv("LP_NUM_THREADS")) {
    const long t = std::strtol(v, nullptr, 10);
    if (t > 0) return uint32_t(std::min<long>(t, 64));
  }
  return std::max(1u, std::thread::hardware_concurrency());
}

RadixSort::RadixSort(gpu::Context& ctx)
    : ctx_(ctx),
      scan_(ctx),
      keys_tmp_(ctx, 16, "sort_keys_tmp"),
      values_tmp_(ctx, 16, "sort_values_tmp"),
      counts_(ctx, 16, "sort_counts"),
      items_(ctx.options().sort_items),
      wide_(ctx.caps().cpu_driver),
      threads_(cpu_threads()) {}

void RadixSort::set_items(uint32_t items) { items_ = items ? std::clamp<uint32_t>(items, 1u, kSortItemsMax) : 0u; }

void RadixSort::set_digit_bits(uint32_t bits) {
  if (bits != 0 && bits != 4 && bits != 8)
    throw gpu::Error("RadixSort: digits of " + std::to_string(bits) + " bits; 4 or 8 (0: the device's choice)");
  wide_ = bits == 0 ? ctx_.caps().cpu_driver : bits == 8;
}

uint32_t RadixSort::group_size() const { return wide_ ? kSortGroupSizeWide : kSortGroupSize; }

uint32_t RadixSort::bins() const { return wide_ ? kSortBinsWide : kSortBins; }

uint32_t RadixSort::items_for(uint32_t n) const {
  if (items_) return items_;
  if (!wide_) return kSortItemsGpu;
  // CPU drivers run one workgroup per thread at a time, so a pass lasts as long as its busiest
  // thread: blocks come in whole rounds of the threads, each block as long as the keys allow
  // (the per-invocation work over the 256 digits is a fixed cost), up to kSortItemsCpu keys an
  // invocation. Whole uvec4s per invocation: a multiple of 4.
  const uint64_t round = uint64_t(threads_) * group_size() * kSortItemsCpu;
  const uint64_t blocks = threads_ * std::max<uint64_t>(1, (uint64_t(n) + round - 1) / round);
  const uint64_t items = (uint64_t(n) + blocks * group_size() - 1) / (blocks * group_size());
  return uint32_t(std::clamp<uint64_t>((items + 3) / 4 * 4, 4, kSortItemsCpu));
}

void RadixSort::reserve(uint32_t n) {
  if (n <= 1) return;
  const uint32_t n_counts = gpu::Commands::div_up(n, group_size() * items_for(n)) * bins();
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
  return record_passes(cmd, keys, values, keys_alt, values_alt, n, bits, false);
}

std::pair<const gpu::Buffer*, const gpu::Buffer*> RadixSort::record_order(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                          gpu::Buffer& order, gpu::Buffer& keys_alt,
                                                                          gpu::Buffer& order_alt, uint32_t n,
                                                                          uint32_t bits) {
  order.ensure(std::max<uint64_t>(n, 1) * 4);
  if (n <= 1) {  // nothing to sort: the permutation of one key
    if (n == 1) cmd.fill(order, 0u, 0, 4);
    return {&keys, &order};
  }
  return record_passes(cmd, keys, order, keys_alt, order_alt, n, bits, true);
}

std::pair<const gpu::Buffer*, const gpu::Buffer*> RadixSort::record_passes(gpu::Commands& cmd, const gpu::Buffer& keys,
                                                                           const gpu::Buffer& values,
                                                                           gpu::Buffer& keys_alt,
                                                                           gpu::Buffer& values_alt, uint32_t n,
                                                                           uint32_t bits, bool order) {
  keys_alt.ensure(uint64_t(n) * 4);
  values_alt.ensure(uint64_t(n) * 4);
  const uint32_t items = items_for(n);
  const uint32_t blocks = gpu::Commands::div_up(n, group_size() * items);
  const uint32_t n_counts = blocks * bins();
  const uint32_t digit_bits = wide_ ? 8u : 4u;
  const std::string count_kernel = wide_ ? "sort/radix_count_wide" : "sort/radix_count";
  const std::string scatter_kernel = wide_ ? "sort/radix_scatter_wide" : "sort/radix_scatter";
  // Few blocks: the scatter scans the raw counts itself, one dispatch fewer per pass.
  const bool fused = wide_ && blocks <= kSortFusedBlocksMax;
  const std::string fused_suffix = fused ? "_fused" : "";
  reserve(n);
  const gpu::Buffer* kin = &keys;
  const gpu::Buffer* vin = &values;
  const gpu::Buffer* kout = &keys_alt;
  const gpu::Buffer* vout = &values_alt;
  // At least one pass when making the permutation (a digit of 0 bits keeps the input order).
  for (uint32_t shift = 0; shift < bits || (order && shift == 0); shift += digit_bits) {
    const uint32_t width = std::min(digit_bits, bits - std::min(bits, shift));
    SortPC pc{n, shift, blocks, items, (1u << width) - 1u};
    cmd.dispatch(count_kernel, {{kRadixCountBindKeys, *kin}, {kRadixCountBindCounts, counts_}}, pc,
                 cmd.linear_groups(blocks));
    if (!fused) scan_.record(cmd, counts_, counts_, n_counts, n_counts);
    if (order && shift == 0)
      cmd.dispatch(scatter_kernel + "_order" + fused_suffix,
                   {{kRadixScatterBindKeysIn, *kin},
                    {kRadixScatterBindKeysOut, *kout},
                    {kRadixScatterBindValuesOut, *vout},
                    {kRadixScatterBindOffsets, counts_}},
                   pc, cmd.linear_groups(blocks));
    else
      cmd.dispatch(scatter_kernel + fused_suffix,
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
