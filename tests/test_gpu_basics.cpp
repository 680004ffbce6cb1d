#include <catch2/catch.hpp>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"

using namespace evflow;

TEST_CASE("gpu: fresh buffers are poisoned in tests and fill/copy work", "[gpu]") {
  auto& ctx = test::gpu_context();
  gpu::Buffer a(ctx, 1024, "a"), b(ctx, 1024, "b");
  auto fresh = a.read<uint32_t>(256);
  for (uint32_t v : fresh) REQUIRE(v == 0xFFFFFFFFu);
  gpu::Commands cmd(ctx);
  cmd.fill(a, 7);
  cmd.copy(a, b, 512);
  cmd.submit();
  auto out = b.read<uint32_t>(256);
  for (int i = 0; i < 128; ++i) REQUIRE(out[i] == 7u);
  for (int i = 128; i < 256; ++i) REQUIRE(out[i] == 0xFFFFFFFFu);
  test::require_no_validation_messages();
}

TEST_CASE("gpu: device limits are queried, not assumed", "[gpu]") {
  auto& caps = test::gpu_context().caps();
  REQUIRE(caps.subgroup_size >= 1);
  REQUIRE(caps.max_workgroup_count[0] >= 65535);
  REQUIRE(caps.max_storage_buffer_range >= (1u << 27));
  gpu::Commands cmd(test::gpu_context());
  auto g = cmd.linear_groups(uint64_t(caps.max_workgroup_count[0]) * 3 + 5);
  REQUIRE(g.x == caps.max_workgroup_count[0]);
  REQUIRE(g.y == 4);
}
