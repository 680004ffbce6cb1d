// The GPU context shared by the tests: validation layer on, fresh buffers poisoned.
// Any validation warning or error fails the run (see main.cpp) and the test that calls
// require_no_validation_messages().
#pragma once
#include <catch2/catch.hpp>

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

}  // namespace evflow::test
