// Requests beyond the device are refused before anything is allocated or recorded, with the
// largest size the device supports.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "gpu_fixture.h"
#include "reference/random_scene.h"
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

// Devices whose binding limit is one intersection short: of the backward's vec4 gradient planes
// (16 B per intersection), where the forward renders and the backward refuses before recording
// anything; of the forward's key buffers (4 B per intersection), where the forward refuses.
TEST_CASE("device limits: intersections beyond the binding limit are refused by the pass that would overrun it",
          "[gpu][limits]") {
  const Camera cam = reference::test_camera(64, 48);
  GaussianCloud cloud = reference::random_scene(7, 2000, 0, cam);
  for (float& s : cloud.log_scales) s += 1.5f;  // larger: several tiles each
  const RenderSettings settings{};
  auto& base = test::gpu_context();
  GaussianBuffers base_params(base, cloud.size(), 0, "lim_");
  base_params.upload(cloud);
  Rasterizer base_raster(base);
  const uint64_t m = base_raster.forward(base_params, cam, settings).num_intersections();
  // Both limits must still hold the images ([3][H][W] floats) and the Gaussians' buffers.
  REQUIRE(m * 4 - 4 >= 64 * 48 * 3 * 4);
  REQUIRE(m * 4 - 4 >= cloud.size() * 16);

  auto device_with_limit = [](uint64_t bytes) {
    gpu::ContextOptions o = gpu::ContextOptions::from_env();
    o.validation = true;
    o.poison = true;
    o.binding_limit = bytes;
    return std::make_unique<gpu::Context>(o);
  };
  {
    auto ctx = device_with_limit(m * 16 - 16);
    REQUIRE(ctx->caps().max_storage_buffer_range == m * 16 - 16);
    GaussianBuffers params(*ctx, cloud.size(), 0, "lim_"), grads(*ctx, cloud.size(), 0, "lim_g_");
    params.upload(cloud);
    Rasterizer raster(*ctx);
    RenderState state = raster.forward(params, cam, settings);
    REQUIRE(state.num_intersections() == m);
    gpu::Buffer v_rgb(*ctx, 64 * 48 * 3 * 4, "lim_v_rgb"), v_alpha(*ctx, 64 * 48 * 4, "lim_v_alpha");
    v_rgb.write(std::vector<float>(64 * 48 * 3, 0.5f));
    v_alpha.write(std::vector<float>(64 * 48, 0.0f));
    REQUIRE_THROWS_WITH(raster.backward(state, params, v_rgb, v_alpha, grads),
                        Catch::StartsWith(std::to_string(m) + " tile intersections exceed, in the backward pass") &&
                            Catch::Contains("(" + std::to_string(m - 1) + " at most)"));
    REQUIRE(ctx->take_validation_messages().empty());
  }
  {
    auto ctx = device_with_limit(m * 4 - 4);
    GaussianBuffers params(*ctx, cloud.size(), 0, "lim_");
    params.upload(cloud);
    Rasterizer raster(*ctx);
    REQUIRE_THROWS_WITH(raster.forward(params, cam, settings),
                        Catch::StartsWith(std::to_string(m) + " tile intersections exceed the storage binding limit") &&
                            Catch::Contains("(" + std::to_string(m - 1) + " at most)"));
    REQUIRE(ctx->take_validation_messages().empty());
  }
  test::require_no_validation_messages();
}
