// Requests beyond the device are refused before anything is allocated or recorded, with the
// largest size the device supports.
#include <catch2/catch.hpp>

#include <string>

#include "gpu_fixture.h"
#include "splat/rasterizer.h"

using namespace evflow;

TEST_CASE("device limits: too many Gaussians are refused up front with the largest supported count", "[gpu][limits]") {
  auto& ctx = test::gpu_context();
  for (int degree : {0, 3}) {
    const size_t largest = GaussianBuffers::max_count(ctx, degree);
    // So many that even the first buffer would exceed the device's largest allocation: only a
    // check made before allocating can answer with the Gaussian count.
    const size_t n = size_t(ctx.caps().max_allocation_size);
    REQUIRE(n > largest);
    REQUIRE_THROWS_WITH(GaussianBuffers(ctx, n, degree, "limits_"),
                        Catch::Contains(std::to_string(n) + " Gaussians at SH degree " + std::to_string(degree)) &&
                            Catch::Contains("the largest supported count is " + std::to_string(largest)));
  }
  test::require_no_validation_messages();
}
