#include "scan/prefix_sum.h"

#include <algorithm>
#include <string>

#include "scan/scan_layout.h"

namespace evflow {

using shaderio::kScanBlock;

void PrefixSum::record(gpu::Commands& cmd, const gpu::Buffer& in, const gpu::Buffer& out, uint32_t n_in,
                       uint32_t n_out) {
  if (n_out == 0) return;
  reserve(n_out);
  record_level(cmd, in, out, n_in, n_out, 0);
}

void PrefixSum::reserve(uint32_t n_out, size_t level) {
  if (n_out == 0) return;
  const uint32_t blocks = gpu::Commands::div_up(n_out, kScanBlock);
  if (sums_.size() <= level) sums_.emplace_back(ctx_, 16, "scan_block_sums");
  sums_[level].ensure(uint64_t(blocks + 1) * 4);
  if (blocks > 1) reserve(blocks, level + 1);
}

void PrefixSum::record_level(gpu::Commands& cmd, const gpu::Buffer& in, const gpu::Buffer& out, uint32_t n_in,
                             uint32_t n_out, size_t level) {
  const uint32_t blocks = gpu::Commands::div_up(n_out, kScanBlock);
  const gpu::Buffer& sums = sums_[level];  // sized by reserve()
  shaderio::ScanPC pc{n_out, n_in, 0, 0};
  const char* suffix = wide_ ? "_wide" : "";
  if (wide_ && level == 0 && blocks > 1 && std::max(n_in, n_out) <= shaderio::kScanSingleMax) {
    cmd.dispatch(
        "scan/scan_block_wide_single",
        {{shaderio::kScanBlockBindIn, in}, {shaderio::kScanBlockBindOut, out}, {shaderio::kScanBlockBindSums, sums}},
        pc, gpu::Groups{1, 1, 1});
    return;
  }
  cmd.dispatch(
      std::string("scan/scan_block") + suffix,
      {{shaderio::kScanBlockBindIn, in}, {shaderio::kScanBlockBindOut, out}, {shaderio::kScanBlockBindSums, sums}}, pc,
      cmd.linear_groups(blocks));
  if (blocks > 1) {
    record_level(cmd, sums, sums, blocks, blocks, level + 1);
    cmd.dispatch(std::string("scan/scan_add") + suffix,
                 {{shaderio::kScanAddBindValues, out}, {shaderio::kScanAddBindOffsets, sums}}, pc,
                 cmd.linear_groups(blocks));
  }
}

}  // namespace evflow
