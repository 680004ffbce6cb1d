// `evflow experiment --emit-jobs` / `--collect`: the emitted lines, run one by one from anywhere,
// give the table the direct run gives.
#include <unistd.h>
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include "cli_helpers.h"
#include "gpu_fixture.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;

namespace {

// The table without its last column (training seconds: wall time, never the same twice).
std::string without_times(const std::string& md) { return std::regex_replace(md, std::regex(" [^|]* \\|\n"), "\n"); }

nlohmann::json runs_without_times(const fs::path& json) {
  nlohmann::json j = nlohmann::json::parse(slurp(json));
  for (auto& r : j["runs"]) r.erase("train_seconds");
  return j;
}

// Two experiments' runs: equal where runs are bit-reproducible; on GPUs, whose float adds come in
// any order, each score within 0.01 and everything else equal.
bool same_runs(const nlohmann::json& a, const nlohmann::json& b) {
  if (test::bit_reproducible()) return a == b;
  nlohmann::json ha = a, hb = b;
  ha.erase("runs");
  hb.erase("runs");
  if (ha != hb || a["runs"].size() != b["runs"].size()) return false;
  for (size_t i = 0; i < a["runs"].size(); ++i)
    for (const auto& [key, v] : a["runs"][i].items()) {
      const nlohmann::json& w = b["runs"][i][key];
      const bool ok =
          v.is_number_float() && w.is_number() ? std::fabs(v.get<double>() - w.get<double>()) <= 0.01 : v == w;
      if (!ok) return false;
    }
  return true;
}

}  // namespace

TEST_CASE("experiment: the emitted job lines, run one by one, collect into the direct run's table",
          "[experiment][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_experiment_jobs");
  fs::create_directories(dir / "elsewhere");
  const std::string tiny =
      " --scenes gallery --blur-px 4 --methods plain,blur-only --refine-iters 1 --width 32 --height 24 "
      "iterations=4 init_gaussians=200 max_gaussians=400 sh_degree=0";
  std::string out;
  int rc = run_evflow(dir, "experiment --out direct" + tiny, out);
  INFO(out);
  REQUIRE(rc == 0);
  const std::string direct_md = slurp(dir / "direct" / "experiment.md");
  REQUIRE(direct_md.find("| gallery | 4 | blur-only |") != std::string::npos);

  rc = run_evflow(dir, "experiment --out batch --emit-jobs jobs.txt" + tiny, out);
  REQUIRE(rc == 0);
  CHECK(!fs::exists(dir / "batch" / "gallery"));  // nothing ran
  std::vector<std::string> lines;
  {
    std::istringstream in(slurp(dir / "jobs.txt"));
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  REQUIRE(lines.size() == 2);  // one per (scene, method)
  CHECK(lines[1].find("--methods 'blur-only'") != std::string::npos);
  // Before the jobs ran, --collect names the runs that are missing.
  CHECK(run_evflow(dir, "experiment --collect batch", out) != 0);
  CHECK(out.find("2 of 2 runs have not finished") != std::string::npos);
  for (const auto& l : lines) {  // from another folder: the lines hold absolute paths
    const std::string cmd = "cd " + quote((dir / "elsewhere").string()) + " && " + l + " > job.log 2>&1";
    INFO(cmd << "\n" << slurp(dir / "elsewhere" / "job.log"));
    REQUIRE(std::system(cmd.c_str()) == 0);
  }
  rc = run_evflow(dir, "experiment --collect batch", out);
  INFO(out);
  REQUIRE(rc == 0);
  if (test::bit_reproducible())
    CHECK(without_times(slurp(dir / "batch" / "experiment.md")) == without_times(direct_md));
  CHECK(without_times(direct_md).find("blur-only | ") != std::string::npos);
  CHECK(same_runs(runs_without_times(dir / "batch" / "experiment.json"),
                  runs_without_times(dir / "direct" / "experiment.json")));
  // Collecting the direct run's folder writes its table again, byte for byte.
  REQUIRE(run_evflow(dir, "experiment --collect direct", out) == 0);
  CHECK(slurp(dir / "direct" / "experiment.md") == direct_md);
  // A folder without a plan is refused, naming the file.
  CHECK(run_evflow(dir, "experiment --collect elsewhere", out) != 0);
  CHECK(out.find("experiment_plan.json") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("experiment: each scene's own blur unless --blur-px is given", "[experiment]") {
  const fs::path dir = evflow::test::fresh_dir("evflow_blur_px");
  std::string out;
  REQUIRE(run_evflow(dir, "experiment --out a --scenes workshop,gallery --methods plain --emit-jobs a.txt", out) == 0);
  const std::string jobs = slurp(dir / "a.txt");
  INFO(jobs);
  CHECK(jobs.find("--scenes 'workshop' --blur-px '9'") != std::string::npos);
  CHECK(jobs.find("--scenes 'gallery' --blur-px '4'") != std::string::npos);
  REQUIRE(run_evflow(dir, "experiment --out b --scenes gallery --blur-px 7 --methods plain --emit-jobs b.txt", out) ==
          0);
  CHECK(slurp(dir / "b.txt").find("--scenes 'gallery' --blur-px '7'") != std::string::npos);
  CHECK(run_evflow(dir, "experiment --out c --scenes gallery --blur-px 7,8 --emit-jobs c.txt", out) != 0);
  CHECK(out.find("--blur-px needs one value per scene (1)") != std::string::npos);
  // One size for several scenes applies to each, with and without --sim-seeds; two for three are refused.
  REQUIRE(run_evflow(dir, "experiment --out d --ablation --scenes workshop,gallery --blur-px 6 --emit-jobs d.txt",
                     out) == 0);
  const std::string one = slurp(dir / "d.txt");
  CHECK(one.find("--scenes 'workshop' --blur-px '6'") != std::string::npos);
  CHECK(one.find("--scenes 'gallery' --blur-px '6'") != std::string::npos);
  CHECK(run_evflow(dir,
                   "experiment --out e --ablation --scenes workshop,gallery,default --blur-px 6,4 --emit-jobs e.txt",
                   out) != 0);
  CHECK(out.find("--blur-px needs one value per scene (3)") != std::string::npos);
  fs::remove_all(dir);
}
