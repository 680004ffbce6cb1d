// evflow simulate on the command line: progress per training view, then the summary; heavier
// meshes by --subdivide, scenes written as glTF; evflow bench sim.
#include <catch2/catch.hpp>

#include <cmath>
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

TEST_CASE("simulate: --subdivide makes a heavier mesh of the same scene, --write-scene writes it as glTF",
          "[cli][sim]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_simulate_subdivide");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --subdivide 3 --write-scene g.glb", out) == 0);
  INFO(out);
  CHECK(out.find("wrote scene gallery (648 triangles) to g.glb") != std::string::npos);
  REQUIRE(fs::exists(dir / "g.glb"));
  // The written file simulates from the built-in scene's cameras (the rig hint travels with it;
  // without it the rig would be derived from the bounds and the views would differ).
  std::string from_file, builtin;
  REQUIRE(run_evflow(dir, "simulate --scene g.glb --out a --width 48 --height 36 --train-views 1 --novel-views 1",
                     from_file) == 0);
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out b --width 48 --height 36 --train-views 1 --novel-views 1",
                     builtin) == 0);
  auto blurry_db = [](const std::string& s) {
    const size_t at = s.find("blurry ");
    REQUIRE(at != std::string::npos);
    return std::stod(s.substr(at + 7));
  };
  INFO(from_file << builtin);
  CHECK(std::abs(blurry_db(from_file) - blurry_db(builtin)) < 0.05);
  CHECK(run_evflow(dir, "simulate --subdivide 0 --write-scene x.glb", out) != 0);
  CHECK(out.find("--subdivide must be 1..1024, got 0") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "x.glb"));
}

TEST_CASE("bench sim: the mesh renderer's stages per frame, as a table or JSON", "[cli][sim]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_bench_sim");
  std::string out;
  REQUIRE(run_evflow(dir, "bench sim --width 64 --height 48 --subdivide 4 --repeats 1 --warmup 0 --json", out) == 0);
  INFO(out);
  CHECK(out.find("\"bench\": \"sim\"") != std::string::npos);
  CHECK(out.find("\"triangles\": 1152") != std::string::npos);
  CHECK(out.find("\"frames\": 16") != std::string::npos);  // the rig's 16 training views, once
  for (const char* stage : {"setup", "scan", "raster small (depth)", "raster tiles (depth)", "raster small (id)",
                            "raster tiles (id)", "shade"})
    CHECK(out.find(std::string("\"") + stage + "\": ") != std::string::npos);
  REQUIRE(run_evflow(dir, "bench sim --width 64 --height 48 --repeats 1 --warmup 0", out) == 0);
  CHECK(out.find("scene default (72 triangles), 64x48, median of 16 frames") != std::string::npos);
  CHECK(run_evflow(dir, "bench sim --scene missing.glb", out) != 0);
  CHECK(out.find("missing.glb") != std::string::npos);
}
