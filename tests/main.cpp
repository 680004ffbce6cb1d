#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "gpu_fixture.h"

namespace evflow::test {

static std::unique_ptr<gpu::Context> g_ctx;

gpu::Context& gpu_context() {
  if (!g_ctx) {
    gpu::ContextOptions o = gpu::ContextOptions::from_env();
    o.validation = true;
    o.sync_validation = true;
    o.poison = true;
    g_ctx = std::make_unique<gpu::Context>(o);
  }
  return *g_ctx;
}

bool gpu_context_exists() { return g_ctx != nullptr; }

void release_gpu_context() { g_ctx.reset(); }

}  // namespace evflow::test

// Takes every "--env NAME=VALUE" out of the arguments and sets it in the environment before
// anything reads it (the Vulkan driver, the programs the tests run). CTest passes the
// environment this way: catch_discover_tests keeps only the first entry of an ENVIRONMENT list.
static std::vector<char*> apply_env_args(int argc, char* argv[]) {
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--env") == 0 && i + 1 < argc && std::strchr(argv[i + 1], '=')) {
      ::putenv(argv[++i]);
      continue;
    }
    rest.push_back(argv[i]);
  }
  return rest;
}

// The exit status CTest reads as "skipped" (SKIP_RETURN_CODE in tests/CMakeLists.txt).
constexpr int kSkipped = 77;

// lavapipe gives 16-lane subgroups only on a CPU with AVX-512; elsewhere a run of the 16-lane
// matrix would run at 8 lanes and pass, having tested nothing new.
static bool lanes_unavailable() {
  const char* expect = std::getenv("EVF_EXPECT_SUBGROUP");
  return expect && std::atoi(expect) > 8 && !__builtin_cpu_supports("avx512f");
}

int main(int argc, char* argv[]) {
  std::vector<char*> args = apply_env_args(argc, argv);
  if (lanes_unavailable()) {
    std::printf("skipped: %s-lane subgroups need AVX-512 on lavapipe; this CPU has none\n",
                std::getenv("EVF_EXPECT_SUBGROUP"));
    return kSkipped;
  }
  int rc = Catch::Session().run(int(args.size()), args.data());
  if (evflow::test::gpu_context_exists()) {
    auto msgs = evflow::test::gpu_context().take_validation_messages();
    for (auto& m : msgs) std::fprintf(stderr, "%s\n", m.c_str());
    if (!msgs.empty()) {
      std::fprintf(stderr, "FAILED: %zu Vulkan validation message(s)\n", msgs.size());
      rc = rc ? rc : 1;
    }
  }
  // Destroyed here, not by a static destructor: at exit the validation layer's own statics
  // (registered after this context's, when the layer was loaded) are gone before it, and
  // GPU-assisted validation touches them while the device is destroyed.
  evflow::test::release_gpu_context();
  return rc;
}
