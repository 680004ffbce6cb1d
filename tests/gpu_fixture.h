// The GPU context shared by the tests: validation layer on, fresh buffers poisoned.
// Any validation warning or error fails the run (see main.cpp) and the test that calls
// require_no_validation_messages().
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "gpu/context.h"

namespace evflow::test {

gpu::Context& gpu_context();
bool gpu_context_exists();
void release_gpu_context();  // before exit (tests/main.cpp)

inline void require_no_validation_messages() {
  auto msgs = gpu_context().take_validation_messages();
  for (auto& m : msgs) UNSCOPED_INFO(m);
  REQUIRE(msgs.empty());
}

// Whether a run on the tests' device is bit-reproducible. A CPU driver runs each workgroup on
// one thread, so the shared-memory float atomics of the backward passes add in one order; a GPU
// adds them in the order its warps arrive, so sums differ in their last bits from run to run.
inline bool bit_reproducible() { return gpu_context().caps().cpu_driver; }

// a == b, exactly where runs are bit-reproducible, else each element within rel of the largest
// magnitude in b (float sums in another order).
inline bool same_values(const std::vector<float>& a, const std::vector<float>& b, double rel = 1e-4) {
  if (bit_reproducible() || a.size() != b.size()) return a == b;
  double scale = 0;
  for (float v : b) scale = std::max(scale, double(std::fabs(v)));
  for (size_t i = 0; i < a.size(); ++i)
    if (!(std::fabs(double(a[i]) - b[i]) <= rel * scale)) return false;
  return true;
}

}  // namespace evflow::test
