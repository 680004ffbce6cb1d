// The lane width the GPU-kernel tests run at: lavapipe takes its subgroup size from
// LP_NATIVE_VECTOR_WIDTH (bits / 32 lanes), and the test command runs those tests at 4, 8 and
// 16 lanes (tests/CMakeLists.txt sets both that width and EVF_EXPECT_SUBGROUP, the lanes meant).
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "gpu_fixture.h"

using namespace evflow;

TEST_CASE("lanes: lavapipe runs at the subgroup size the test matrix asks for", "[lanes][gpu]") {
  const auto& caps = test::gpu_context().caps();
  std::printf("lanes: device %s, subgroup size %u\n", caps.name.c_str(), caps.subgroup_size);
  const char* expect = std::getenv("EVF_EXPECT_SUBGROUP");
  if (!caps.cpu_driver || !expect) {
    SUCCEED("not lavapipe, or not a run of the lane matrix");
    return;
  }
  // (Without AVX-512 the 16-lane runs never get here: tests/main.cpp reports them skipped.)
  const uint32_t lanes = uint32_t(std::stoul(expect));
  REQUIRE(caps.subgroup_size == lanes);
}
