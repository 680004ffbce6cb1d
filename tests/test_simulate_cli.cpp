// evflow simulate on the command line: progress per training view, then the summary.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "cli_helpers.h"

using namespace evflow::test;
namespace fs = std::filesystem;

TEST_CASE("simulate: a progress line per training view with the sub-frames and an ETA, then the summary",
          "[cli][sim]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_simulate_cli");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --out sim --width 32 --height 24 --train-views 3 --novel-views 1", out) == 0);
  INFO(out);
  size_t at = 0;
  for (int v = 1; v <= 3; ++v) {
    const size_t line = out.find("view " + std::to_string(v) + "/3 simulated (", at);
    REQUIRE(line != std::string::npos);  // in order
    const size_t end = out.find('\n', line);
    CHECK(out.substr(line, end - line).find("sub-frame intervals), ") != std::string::npos);
    CHECK(out.substr(line, end - line).find("ETA ") != std::string::npos);
    at = end;
  }
  CHECK(out.find("view 4/3") == std::string::npos);
  CHECK(out.find("simulate: wrote sim", at) != std::string::npos);
}
