#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <initializer_list>
#include <string>
#include <vector>

#include "common/common_layout.h"
#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "gpu/staging.h"
#include "gpu_fixture.h"
#include "splat/splat_layout.h"

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

TEST_CASE("gpu: dispatches past 65,535 workgroups reach every element", "[gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t groups = 70000, n = groups * shaderio::kIotaGroupSize - 5;
  gpu::Buffer b(ctx, uint64_t(n) * 4, "iota");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{n, 3};
  auto g = cmd.linear_groups(groups);
  REQUIRE((g.y >= 2) == (groups > ctx.caps().max_workgroup_count[0]));  // GPUs allow 2^31 - 1
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, g);
  cmd.submit();
  auto v = b.read<uint32_t>(n);
  bool ok = true;
  for (uint32_t i = 0; i < n; ++i) ok = ok && v[i] == i + 3;
  REQUIRE(ok);
  test::require_no_validation_messages();
}

TEST_CASE("gpu: a binding above the device's storage range is refused with a clear message", "[gpu]") {
  // A device whose binding range is lowered to 4 KiB, so that the refusal runs on every device
  // (a GPU's range can exceed the largest buffer it allocates).
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.binding_limit = 4096;
  gpu::Context ctx(o);
  REQUIRE(ctx.caps().max_storage_buffer_range == 4096);
  gpu::Buffer big(ctx, 4096 + 1024, "too_big"), fits(ctx, 4096, "fits");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{16, 0};
  REQUIRE_THROWS_WITH(cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, big}}, pc, gpu::Groups{1, 1, 1}),
                      Catch::Contains("too_big") && Catch::Contains("maxStorageBufferRange"));
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, fits}}, pc, gpu::Groups{1, 1, 1});
  cmd.submit();
  CHECK(fits.read<uint32_t>(16)[15] == 15u);
  REQUIRE(ctx.take_validation_messages().empty());
}

TEST_CASE("gpu: buffer textures bind as texel buffer views, within the device's texel limit", "[gpu]") {
  // The block compositing kernel reads the sorted slots and Gaussian ids as R32UI texels and the
  // projected Gaussians as RGBA32F texels (samplerBuffer / usamplerBuffer), named by variable.
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.binding_limit = 4096;  // and 1024 texels
  gpu::Context ctx(o);
  REQUIRE(ctx.caps().max_texel_buffer_elements == 1024);
  const auto& k = ctx.kernel("splat/rasterize_block");
  auto binding = [&](const shaderio::BindSlot& s) {
    for (const gpu::Kernel::Binding& b : k.bindings())
      if (b.index == s.index) return b;
    FAIL("no binding " << s.index);
    return gpu::Kernel::Binding{};
  };
  using namespace shaderio;
  CHECK(binding(kRasterBindRanges).texel_format == VK_FORMAT_UNDEFINED);
  CHECK(binding(kRasterBindSlots).texel_format == VK_FORMAT_R32_UINT);
  CHECK(binding(kRasterBindGid).texel_format == VK_FORMAT_R32_UINT);
  for (const BindSlot& s : {kRasterBindProjA, kRasterBindProjB, kRasterBindProjC}) {
    CHECK(binding(s).texel_format == VK_FORMAT_R32G32B32A32_SFLOAT);
    CHECK(binding(s).block == s.block);
  }
  // 1025 RGBA32F texels at ProjA are one too many; the storage bindings fit.
  gpu::Buffer fits(ctx, 4096, "fits"), too_many(ctx, 1025 * 16, "too_many_texels");
  std::vector<gpu::Bind> binds;
  for (const gpu::Kernel::Binding& b : k.bindings())
    binds.push_back({BindSlot{b.index, b.block.c_str()}, b.index == kRasterBindProjA.index ? too_many : fits});
  gpu::Commands cmd(ctx);
  RasterPC pc{};
  REQUIRE_THROWS_WITH(cmd.dispatch("splat/rasterize_block", binds, pc, gpu::Groups{1, 1, 1}),
                      Catch::Contains("too_many_texels") && Catch::Contains("1025 texels") &&
                          Catch::Contains("maxTexelBufferElements of 1024"));
  REQUIRE(ctx.take_validation_messages().empty());
}

TEST_CASE("gpu: dispatch binds by name and checks the bindings against the kernel's SPIR-V", "[gpu]") {
  auto& ctx = test::gpu_context();
  gpu::Buffer a(ctx, 256, "a"), b(ctx, 256, "b");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{16, 0};
  const gpu::Groups one{1, 1, 1};
  const auto& k = ctx.kernel("common/iota");
  REQUIRE(k.bindings().size() == 1);
  CHECK(k.bindings()[0].index == shaderio::kIotaBindValues.index);
  CHECK(k.bindings()[0].block == "Values");
  // A binding the shader lacks, one bound twice, one missing, one under another block's name.
  REQUIRE_THROWS_WITH(
      cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, a}, {shaderio::BindSlot{1, "Extra"}, b}}, pc, one),
      Catch::Contains("'common/iota' has no binding 1 (Extra)") && Catch::Contains("declares 0 (Values)"));
  REQUIRE_THROWS_WITH(
      cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, a}, {shaderio::kIotaBindValues, b}}, pc, one),
      Catch::Contains("binding 0 (Values) is bound twice"));
  REQUIRE_THROWS_WITH(cmd.dispatch("common/iota", {}, pc, one), Catch::Contains("binding 0 (Values) is not bound"));
  REQUIRE_THROWS_WITH(cmd.dispatch("common/iota", {{shaderio::BindSlot{0, "Keys"}, a}}, pc, one),
                      Catch::Contains("binding 0 is block 'Values' in its SPIR-V, the host binds 'Keys'"));
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, a}}, pc, one);
  cmd.submit();
  CHECK(a.read<uint32_t>(16)[15] == 15u);
  test::require_no_validation_messages();
}

TEST_CASE("gpu: GPU-assisted validation reports a write past the end of a buffer", "[gpu][gpu-av]") {
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.gpu_validation = true;
  gpu::Context ctx(o);
  REQUIRE(ctx.bound_descriptor_sets());
  gpu::Buffer b(ctx, 64, "values");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{16, 0};
  // Within the buffer: no message.
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, gpu::Groups{1, 1, 1});
  cmd.submit();
  CHECK(b.read<uint32_t>(16)[15] == 15u);
  CHECK(ctx.take_validation_messages().empty());
  // 32 values into a 16-value buffer: the instrumented shader skips and reports the writes past
  // its end (the layer checks against the whole buffer, not the bound range).
  pc.n = 32;
  pc.offset = 100;
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, gpu::Groups{1, 1, 1});
  cmd.submit();
  CHECK(b.read<uint32_t>(16)[15] == 115u);
  const std::vector<std::string> msgs = ctx.take_validation_messages();
  REQUIRE_FALSE(msgs.empty());
  CHECK_THAT(msgs[0], Catch::Contains("out of bounds", Catch::CaseSensitive::No));
}

TEST_CASE("gpu: the context counts its buffers' device memory, now and at its peak", "[gpu]") {
  auto& ctx = test::gpu_context();
  const uint64_t before = ctx.device_bytes();
  {
    gpu::Buffer a(ctx, 1 << 20, "a");
    CHECK(ctx.device_bytes() >= before + (1 << 20));
    gpu::Buffer b(ctx, 1 << 20, "b");
    CHECK(ctx.device_bytes() >= before + (2 << 20));
    gpu::Buffer moved = std::move(a);  // a move changes nothing
    CHECK(ctx.device_bytes() >= before + (2 << 20));
    b.ensure(4 << 20);  // grown to 5 MiB (25 % headroom): the old memory is returned, the new counted
    CHECK(ctx.device_bytes() >= before + (1 << 20) + (5 << 20));
    CHECK(ctx.device_bytes() < before + (2 << 20) + (5 << 20));
  }
  CHECK(ctx.device_bytes() == before);
  CHECK(ctx.peak_device_bytes() >= before + (6 << 20));
}

TEST_CASE("gpu: commands recorded on a buffer that is then grown are refused at submit, naming it", "[gpu]") {
  auto& ctx = test::gpu_context();
  gpu::Buffer b(ctx, 64 * 4, "scratch");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{64, 0};
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, cmd.linear_groups(1));
  b.ensure(1 << 20);  // frees the allocation the dispatch recorded
  REQUIRE_THROWS_WITH(cmd.submit(), Catch::Contains("'scratch'") && Catch::Contains("grown or freed"));
  // The commands start afresh and work after the refusal.
  pc.offset = 7;
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, cmd.linear_groups(1));
  cmd.submit();
  REQUIRE(b.read<uint32_t>(64)[63] == 70u);
  test::require_no_validation_messages();
}

TEST_CASE("gpu: a device without host-visible memory copies through one staging buffer, in pieces past its cap",
          "[gpu]") {
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.sync_validation = true;
  o.poison = true;
  o.staged_transfers = true;  // as a discrete GPU: buffers unmapped, every copy staged
  gpu::Context ctx(o);
  REQUIRE_FALSE(ctx.caps().unified_memory);
  // Small copies: one submit each, through a staging buffer made once and kept.
  gpu::Buffer small(ctx, 4096, "small");
  std::vector<uint32_t> v(1024);
  for (uint32_t i = 0; i < v.size(); ++i) v[i] = i * 2654435761u;
  const uint64_t submits0 = ctx.submits(), transfers0 = ctx.transfers();
  small.write(v);
  REQUIRE(small.read<uint32_t>(v.size()) == v);
  CHECK(ctx.submits() - submits0 == 2);
  CHECK(ctx.transfers() - transfers0 == 2);
  const uint64_t cap = ctx.staging().capacity();
  REQUIRE(cap >= 4096);
  // A copy larger than the staging cap goes in pieces, at an offset, and leaves the rest intact.
  const uint64_t words = gpu::Staging::kMaxBytes / 4 + 1000, offset_words = 7;
  gpu::Buffer big(ctx, (words + offset_words + 1) * 4, "big");
  std::vector<uint32_t> w(words);
  for (uint64_t i = 0; i < words; ++i) w[i] = uint32_t(i ^ 0x5bd1e995u);
  big.upload(w.data(), words * 4, offset_words * 4);
  CHECK(ctx.staging().capacity() == gpu::Staging::kMaxBytes);
  const std::vector<uint32_t> back = big.read<uint32_t>(words + offset_words + 1);
  CHECK(std::equal(w.begin(), w.end(), back.begin() + offset_words));
  CHECK(back[0] == 0xFFFFFFFFu);  // poisoned in tests, untouched by the copy
  CHECK(back[words + offset_words] == 0xFFFFFFFFu);
  REQUIRE(ctx.take_validation_messages().empty());
}

namespace {

// Environment variable `name` read by ContextOptions::from_env into `field`: `good` gives `expect`,
// every one of `bad` is refused naming the variable, unset gives 0; its old value is restored.
template <typename Field>
void check_env_whole(const char* name, const char* good, uint64_t expect, std::initializer_list<const char*> bad,
                     Field field) {
  const char* was = std::getenv(name);
  const std::string saved = was ? was : "";
  setenv(name, good, 1);
  CHECK(uint64_t(field(gpu::ContextOptions::from_env())) == expect);
  for (const char* b : bad) {
    INFO(name << "='" << b << "'");
    setenv(name, b, 1);
    CHECK_THROWS_WITH(gpu::ContextOptions::from_env(), Catch::Contains(std::string(name) + " must be a whole number"));
  }
  unsetenv(name);
  CHECK(uint64_t(field(gpu::ContextOptions::from_env())) == 0);
  if (was) setenv(name, saved.c_str(), 1);
}

}  // namespace

TEST_CASE("gpu: the kernel overrides in the environment are checked, naming the variable", "[gpu]") {
  check_env_whole("EVF_SORT_ITEMS", "64", 64, {"0", "4097", "abc", "12x", ""},
                  [](const gpu::ContextOptions& o) { return o.sort_items; });
  check_env_whole("EVF_BINDING_LIMIT", "1048576", 1048576,
                  {"0", "8", "-5", "1e6", "abc", "64k", "", "99999999999999999999999"},
                  [](const gpu::ContextOptions& o) { return o.binding_limit; });
}

TEST_CASE(
    "gpu: under GPU-assisted validation the context makes every shader's module first, and each kernel takes its own",
    "[gpu]") {
  // Why: create_embedded_modules (gpu/kernel.h).
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.gpu_validation = true;
  {
    gpu::Context ctx(o);
    ctx.kernel("scan/scan_add");  // takes its module
    REQUIRE(ctx.take_module("scan/scan_add") == VK_NULL_HANDLE);
    for (const char* name : {"splat/project", "nn/relu", "sort/radix_count_wide"}) {
      INFO(name);
      VkShaderModule m = ctx.take_module(name);
      REQUIRE(m != VK_NULL_HANDLE);
      REQUIRE(ctx.take_module(name) == VK_NULL_HANDLE);  // handed over once
      vkDestroyShaderModule(ctx.device(), m, nullptr);
    }
    REQUIRE(ctx.take_module("no/such_kernel") == VK_NULL_HANDLE);
    REQUIRE(ctx.take_validation_messages().empty());
  }
  // Without it, kernels make their modules when they are first used.
  o.gpu_validation = false;
  gpu::Context plain(o);
  REQUIRE(plain.take_module("splat/project") == VK_NULL_HANDLE);
}

// With kernel times on, every dispatch writes a timestamp: the context collects each dispatch's
// time under its kernel's name, and the stages still span what they did.
TEST_CASE("gpu: kernel times name each dispatch by its kernel and lie within its stage", "[gpu]") {
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.kernel_times = true;
  gpu::Context ctx(o);
  if (!ctx.caps().timestamps) {
    WARN("the device has no timestamps: nothing to time");
    return;
  }
  const uint32_t n = 1u << 20;
  gpu::Buffer b(ctx, uint64_t(n) * 4, "iota");
  gpu::Commands cmd(ctx);
  struct {
    uint32_t n, offset;
  } pc{n, 0};
  const gpu::Groups g = cmd.linear_groups(n / shaderio::kIotaGroupSize);
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, g);
  cmd.fill(b, 0u);
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, g);
  cmd.mark("two");
  cmd.dispatch("scan/scan_add", {}, pc, gpu::Groups{0, 1, 1});  // no workgroups: not recorded, no time
  cmd.dispatch("common/iota", {{shaderio::kIotaBindValues, b}}, pc, g);
  cmd.mark("one");
  cmd.submit();
  const auto kernels = ctx.take_kernel_times();
  REQUIRE(kernels.size() == 3);
  for (const auto& [name, ms] : kernels) {
    CHECK(name == "common/iota");
    CHECK(ms >= 0.0);
  }
  REQUIRE(cmd.stage_ms().size() == 2);
  CHECK(cmd.stage_ms()[0].first == "two");
  CHECK(cmd.stage_ms()[1].first == "one");
  // A stage spans its dispatches (and, in the first, the fill between them).
  CHECK(cmd.stage_ms()[0].second >= kernels[0].second + kernels[1].second - 1e-9);
  CHECK(cmd.stage_ms()[1].second >= kernels[2].second - 1e-9);
  CHECK(ctx.take_kernel_times().empty());  // taken
  // Off: the same stages, no kernel times.
  o.kernel_times = false;
  gpu::Context plain(o);
  gpu::Buffer c(plain, uint64_t(n) * 4, "iota");
  gpu::Commands pcmd(plain);
  pcmd.dispatch("common/iota", {{shaderio::kIotaBindValues, c}}, pc, g);
  pcmd.mark("one");
  pcmd.submit();
  CHECK(plain.take_kernel_times().empty());
  REQUIRE(pcmd.stage_ms().size() == 1);
  CHECK(pcmd.stage_ms()[0].first == "one");
  CHECK(ctx.take_validation_messages().empty());
  CHECK(plain.take_validation_messages().empty());
}
