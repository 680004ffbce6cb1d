// `evflow experiment --ablation`: the paper's seven ablation rows, each trained with exactly the
// terms its row names (the loss columns of its curve), and their table.
#include <unistd.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_helpers.h"
#include "io/dataset.h"
#include "io/image.h"
#include "metrics/srgb_metrics.h"
#include "train/train_config.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;

namespace {

// The loss columns a run's curve.csv has for each of the table's terms after L_blur^gs.
const char* const kTermColumns[] = {",events,",   ",events_warped,", ",residual,",
                                    ",ldi_blur,", ",ldi_events,",    ",joint,"};

// The paper's Table 3: each row's method and its terms L_ev, L_ev^w, L_res, L_blur^ldi,
// L_ev^ldi, L_joint (L_blur^gs in every row).
struct Row {
  const char* method;
  std::array<bool, 6> terms;
};
const Row kRows[] = {
    {"blur-only", {false, false, false, false, false, false}},
    {"blur+events", {true, false, false, false, false, false}},
    {"blur+events+warp", {true, true, false, false, false, false}},
    {"blur+res", {false, false, true, false, false, false}},
    {"blur+events+warp+res", {true, true, true, false, false, false}},
    {"evflow-no-ldi-events", {true, true, true, true, false, true}},
    {"evflow", {true, true, true, true, true, true}},
};

std::string curve_header(const fs::path& run) {
  const std::string csv = slurp(run / "curve.csv");
  return csv.substr(0, csv.find('\n')) + ",";
}

}  // namespace

TEST_CASE("experiment --ablation: seven rows, each trained with the terms its row names, in one table",
          "[experiment][gpu][ldi]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_ablation");
  std::string out;
  const int rc = run_evflow(dir,
                            "experiment --out abl --ablation --scenes gallery --blur-px 4 --sim-seeds 3 "
                            "--refine-iters 1 --width 32 --height 24 iterations=6 init_gaussians=200 "
                            "max_gaussians=400 sh_degree=0 ldi_init_steps=2 ldi_crop=16",
                            out);
  INFO(out);
  REQUIRE(rc == 0);
  for (const Row& row : kRows) {
    INFO(row.method);
    const std::string header = curve_header(dir / "abl" / "gallery-s3" / row.method);
    CHECK(header.rfind("step,view,loss,ms,flipped,l1_ssim,", 0) == 0);  // L_blur^gs: every row
    for (size_t t = 0; t < 6; ++t) CHECK((header.find(kTermColumns[t]) != std::string::npos) == row.terms[t]);
  }
  const std::string md = slurp(dir / "abl" / "ablation.md");
  CHECK(md.find("| VII | ✓ | ✓ | ✓ | ✓ | ✓ | ✓ | ✓ | evflow | 1 |") != std::string::npos);
  CHECK(md.find("| IV | ✓ |  |  | ✓ |  |  |  | blur+res | 1 |") != std::string::npos);
  CHECK(md.find("gallery-s3 |") != std::string::npos);
  // eval scores the LDI's own mid-exposure frames in runs with the branch: re-scoring the PNGs
  // it wrote against the sharp frames gives its figures.
  const fs::path scene = dir / "abl" / "gallery-s3";
  CHECK(!nlohmann::json::parse(slurp(scene / "blur-only" / "eval.json")).contains("ldi"));
  const nlohmann::json e = nlohmann::json::parse(slurp(scene / "evflow" / "eval.json"));
  const io::Dataset data = io::load_dataset(scene / "data");
  REQUIRE(e.contains("ldi"));
  REQUIRE(e["ldi"]["views"].size() == data.train.size());
  for (size_t v = 0; v < data.train.size(); ++v) {
    const io::View& view = data.train[v];
    const io::Image png = io::read_image(scene / "evflow" / "eval" / "ldi" / (view.name + ".png"));
    const auto rescored =
        metrics::score(metrics::encode_linear(io::planar_rgb(png), png.width, png.height, 3),
                       metrics::encode_linear(io::planar_rgb(*view.sharp_mid), png.width, png.height, 3));
    CHECK(e["ldi"]["views"][v]["psnr"].get<double>() == Approx(rescored.psnr).epsilon(1e-12));
    CHECK(e["ldi"]["views"][v]["ssim"].get<double>() == Approx(rescored.ssim).epsilon(1e-12));
  }
  fs::remove_all(dir);
}

TEST_CASE("experiment --ablation: refuses --methods and mixed seed options", "[experiment]") {
  const fs::path dir = fresh_dir("evflow_ablation_args");
  std::string out;
  CHECK(run_evflow(dir, "experiment --out x --ablation --methods plain --emit-jobs j.txt", out) != 0);
  CHECK(out.find("--ablation sets the methods") != std::string::npos);
  CHECK(run_evflow(dir, "experiment --out x --sim-seed 1 --sim-seeds 1,2 --emit-jobs j.txt", out) != 0);
  CHECK(out.find("exclude each other") != std::string::npos);
  // Two seeds of the four built-in scenes: eight folders, seven rows each.
  REQUIRE(run_evflow(dir, "experiment --out x --ablation --emit-jobs j.txt", out) == 0);
  const std::string jobs = slurp(dir / "j.txt");
  CHECK(std::count(jobs.begin(), jobs.end(), '\n') == 4 * 2 * 7);
  CHECK(jobs.find("--scenes 'workshop' --blur-px '9' --methods 'evflow'") != std::string::npos);
  CHECK(jobs.find("--sim-seeds 2") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("train config: the ablation's methods set their terms and do not stack", "[train][config]") {
  TrainConfig c;
  c.apply_method("evflow");
  CHECK((c.event_weight == 0.1 && c.warp_weight == 0.1 && c.res_weight == 0.1 && c.ldi && c.ldi_event_weight == 0.1));
  c.apply_method("evflow-no-ldi-events");
  CHECK((c.ldi && c.ldi_event_weight == 0));
  c.apply_method("blur+res");
  CHECK((c.mode == TrainMode::Blur && c.event_weight == 0 && c.res_weight == 0.1 && !c.ldi));
  c.apply_method("blur-only");
  CHECK((c.res_weight == 0 && !c.ldi && c.warp_weight == 0 && c.ldi_event_weight == 0.1));
}
