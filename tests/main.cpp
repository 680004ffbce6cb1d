#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdio>
#include <memory>

#include "gpu_fixture.h"

namespace evflow::test {

static std::unique_ptr<gpu::Context> g_ctx;

gpu::Context& gpu_context() {
  if (!g_ctx) {
    gpu::ContextOptions o = gpu::ContextOptions::from_env();
    o.validation = true;
    o.poison = true;
    g_ctx = std::make_unique<gpu::Context>(o);
  }
  return *g_ctx;
}

bool gpu_context_exists() { return g_ctx != nullptr; }

}  // namespace evflow::test

int main(int argc, char* argv[]) {
  int rc = Catch::Session().run(argc, argv);
  if (evflow::test::gpu_context_exists()) {
    auto msgs = evflow::test::gpu_context().take_validation_messages();
    for (auto& m : msgs) std::fprintf(stderr, "%s\n", m.c_str());
    if (!msgs.empty()) {
      std::fprintf(stderr, "FAILED: %zu Vulkan validation message(s)\n", msgs.size());
      rc = rc ? rc : 1;
    }
  }
  return rc;
}
