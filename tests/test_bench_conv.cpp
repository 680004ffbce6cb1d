// evflow bench conv: per-layer figures as JSON for the stack it was given, and clear refusals.
#include <sys/wait.h>

#include <catch2/catch.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli_helpers.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;

TEST_CASE("bench conv: JSON with one entry per layer, their MACs, times and GFLOP/s", "[cli][nn]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_bench_conv");
  std::string out;
  REQUIRE(run_evflow(dir, "bench conv --width 21 --height 13 --widths 4,8,1 --repeats 1 --warmup 0 --json", out) == 0);
  const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
  CHECK(b["widths"] == nlohmann::json::array({4, 8, 1}));
  REQUIRE(b["layers"].size() == 2);
  CHECK(b["layers"][0]["macs"] == 21 * 13 * 9 * 4 * 8);
  CHECK(b["layers"][1]["macs"] == 21 * 13 * 9 * 8 * 1);
  for (auto& l : b["layers"]) {
    CHECK(l["forward_ms"].get<double>() > 0);
    CHECK(l["backward_gflops"].get<double>() > 0);
  }
  CHECK(b["cpu_seconds"].get<double>() >= 0);
  CHECK(run_evflow(dir, "bench conv --widths 4", out) != 0);
  CHECK(out.find("--widths needs the input width and at least one layer") != std::string::npos);
  CHECK(run_evflow(dir, "bench conv --widths 4,x", out) != 0);
  CHECK(out.find("'x' is not a width") != std::string::npos);
}
