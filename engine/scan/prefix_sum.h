// Exclusive prefix sum of a uint buffer on the GPU (multi-level: blocks of 4096, then the block
// sums, recursively). Correct for any subgroup size: it uses shared memory only.
#pragma once
#include <deque>

#include "gpu/commands.h"

namespace evflow {

class PrefixSum {
 public:
  explicit PrefixSum(gpu::Context& ctx) : ctx_(ctx), wide_(ctx.caps().cpu_driver) {}
  // Workgroups of 16 invocations of 256 elements (the "_wide" kernels: CPU drivers, the default
  // there) or of 256 invocations of 16 (GPUs), for every record from now on.
  void set_wide(bool wide) { wide_ = wide; }
  // out[i] = in[0] + ... + in[i-1] for i < n_out, reading in[i] for i < n_in (zero beyond), so
  // n_out = n_in + 1 leaves the total in out[n_in]. `in` and `out` may be the same buffer.
  void record(gpu::Commands& cmd, const gpu::Buffer& in, const gpu::Buffer& out, uint32_t n_in, uint32_t n_out);
  // Grows the block sums for an n_out-long scan (before recording several scans of different
  // lengths into one command buffer, so none is regrown under recorded commands).
  void reserve(uint32_t n_out, size_t level = 0);

 private:
  void record_level(gpu::Commands& cmd, const gpu::Buffer& in, const gpu::Buffer& out, uint32_t n_in, uint32_t n_out,
                    size_t level);
  gpu::Context& ctx_;
  std::deque<gpu::Buffer> sums_;  // deque: references stay valid while deeper levels are added
  bool wide_;
};

}  // namespace evflow
