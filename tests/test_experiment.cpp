// `evflow experiment`: a scene's simulated data follow the scene, not its place in --scenes.
#include <sys/wait.h>
#include <unistd.h>
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>
#include "cli_helpers.h"

#include "io/dataset.h"
#include "io/image.h"
#include "metrics/srgb_metrics.h"
#include "sim/builtin_scenes.h"
#include "sim/gltf_scene.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;

TEST_CASE("experiment: a scene is simulated with its own seed wherever it is listed, bad seeds and scenes refused",
          "[experiment][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_experiment_test");
  const std::string size = " --width 32 --height 24 --pose-noise-rot 0.4 --pose-noise-trans 0.01";
  std::string out;

  // gallery alone: the tiniest run that simulates, trains, evaluates and writes the table.
  int rc = run_evflow(dir,
                      "experiment --out exp --scenes gallery --blur-px 4 --methods plain --refine-iters 1" + size +
                          " iterations=4 init_gaussians=200 max_gaussians=400 sh_degree=0",
                      out);
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(fs::exists(dir / "exp" / "experiment.json"));
  CHECK(slurp(dir / "exp" / "experiment.md").find("| gallery | 4 | plain |") != std::string::npos);
  // What a seed decides, byte-stable (dataset.json also holds the run's timings): the recorded
  // poses (their noise) and the blurry images (the camera shake).
  auto data_of = [](const fs::path& d) { return slurp(d / "poses_bounds.npy") + slurp(d / "images" / "000.png"); };
  const std::string listed = data_of(dir / "exp" / "gallery" / "data");
  REQUIRE(listed.size() > 1000);

  // gallery is the second built-in scene: seed 2, as in the full list (default, gallery, workshop).
  const std::string sim = "simulate --scene gallery --blur-px 4" + size;
  REQUIRE(run_evflow(dir, sim + " --out s2 --seed 2", out) == 0);
  REQUIRE(run_evflow(dir, sim + " --out s1 --seed 1", out) == 0);
  CHECK(data_of(dir / "s2") == listed);
  CHECK(data_of(dir / "s1") != listed);  // the seed matters

  // --sim-seed overrides the per-scene seed.
  rc = run_evflow(dir,
                  "experiment --out exp1 --scenes gallery --blur-px 4 --methods plain --refine-iters 1 --sim-seed 1" +
                      size + " iterations=4 init_gaussians=200 max_gaussians=400 sh_degree=0",
                  out);
  INFO(out);
  REQUIRE(rc == 0);
  CHECK(data_of(dir / "exp1" / "gallery" / "data") == data_of(dir / "s1"));

  // --shake jerk reaches the simulator, the plan and the emitted job lines.
  rc = run_evflow(dir,
                  "experiment --out exp2 --scenes gallery --blur-px 4 --methods plain --refine-iters 1 --sim-seed 1 "
                  "--shake jerk" +
                      size + " iterations=4 init_gaussians=200 max_gaussians=400 sh_degree=0",
                  out);
  INFO(out);
  REQUIRE(rc == 0);
  REQUIRE(run_evflow(dir, sim + " --out j1 --seed 1 --shake jerk", out) == 0);
  CHECK(data_of(dir / "exp2" / "gallery" / "data") == data_of(dir / "j1"));
  CHECK(data_of(dir / "j1") != data_of(dir / "s1"));
  REQUIRE(run_evflow(dir,
                     "experiment --out exp3 --scenes gallery --blur-px 4 --methods plain --sim-seed 1 --shake jerk "
                     "--emit-jobs jobs.txt" +
                         size,
                     out) == 0);
  CHECK(slurp(dir / "jobs.txt").find(" --shake 'jerk'") != std::string::npos);
  CHECK(slurp(dir / "exp3" / "experiment_plan.json").find("\"shake\": \"jerk\"") != std::string::npos);

  // Refused before any work.
  CHECK(run_evflow(dir, "experiment --out bad --scenes gallery --blur-px 4 --shake wobble", out) != 0);
  CHECK(out.find("--shake") != std::string::npos);
  CHECK(run_evflow(dir, "experiment --out bad --scenes gallery --blur-px 4 --sim-seed x", out) != 0);
  CHECK(out.find("--sim-seed") != std::string::npos);
  CHECK(run_evflow(dir, "experiment --out bad --scenes nowhere --blur-px 4", out) != 0);
  CHECK(out.find("nowhere") != std::string::npos);
  CHECK(!fs::exists(dir / "bad" / "nowhere"));
  fs::remove_all(dir);
}

TEST_CASE(
    "experiment: a scene file runs end to end under DIR/<file stem>, baselines refine their poses unless told not to",
    "[experiment][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_experiment_file");
  fs::create_directories(dir / "scenes");
  sim::write_gltf(sim::make_builtin_scene("gallery"), dir / "scenes" / "some.glb");
  const std::string tiny =
      " --width 32 --height 24 --blur-px 4 --refine-iters 1 iterations=6 init_gaussians=200 "
      "max_gaussians=400 sh_degree=0 event_from=0";
  std::string out;
  int rc = run_evflow(
      dir, "experiment --out exp --scenes scenes/some.glb --sim-seed 5 --methods plain,blur+events" + tiny, out);
  INFO(out);
  REQUIRE(rc == 0);
  const fs::path exp = dir / "exp" / "some";
  CHECK(fs::exists(exp / "data" / "dataset.json"));
  CHECK(!fs::exists(dir / "scenes" / "some.glb" / "data"));
  CHECK(slurp(dir / "exp" / "experiment.md").find("| some | 4 | plain |") != std::string::npos);
  CHECK(slurp(dir / "exp" / "experiment.md").find("| some | 4 | blur+events |") != std::string::npos);
  // The data follow --sim-seed: the same as simulating the file with seed 5.
  auto data_of = [](const fs::path& d) { return slurp(d / "poses_bounds.npy") + slurp(d / "images" / "000.png"); };
  REQUIRE(run_evflow(dir,
                     "simulate --scene scenes/some.glb --out s5 --seed 5 --width 32 --height 24 --blur-px 4 "
                     "--pose-noise-rot 0.4 --pose-noise-trans 0.01",
                     out) == 0);
  CHECK(data_of(exp / "data") == data_of(dir / "s5"));
  // Every run was evaluated on 8-bit sRGB images, and eval wrote the renders it scored: re-scoring
  // those PNGs against the sharp frames gives eval.json's figures.
  const io::Dataset data = io::load_dataset(exp / "data");
  for (const char* m : {"plain", "blur+events"}) {
    const nlohmann::json e = nlohmann::json::parse(slurp(exp / m / "eval.json"));
    REQUIRE(e["deblur"]["views"].size() == data.train.size());
    for (size_t v = 0; v < data.train.size(); ++v) {
      const io::View& view = data.train[v];
      const io::Image png = io::read_image(exp / m / "eval" / "deblur" / (view.name + ".png"));
      const auto rescored =
          metrics::score(metrics::encode_linear(io::planar_rgb(png), png.width, png.height, 3),
                         metrics::encode_linear(io::planar_rgb(*view.sharp_mid), png.width, png.height, 3));
      CHECK(e["deblur"]["views"][v]["view"] == view.name);
      CHECK(e["deblur"]["views"][v]["psnr"].get<double>() == Approx(rescored.psnr).epsilon(1e-12));
      CHECK(e["deblur"]["views"][v]["ssim"].get<double>() == Approx(rescored.ssim).epsilon(1e-12));
    }
  }
  // plain refines its training poses (its checkpoint holds one 6-vector per view); blur+events
  // has its trajectories; with --no-baseline-pose-refine plain does not refine.
  CHECK(slurp(exp / "plain" / "config.json").find("\"pose_refine\": true") != std::string::npos);
  rc = run_evflow(
      dir,
      "experiment --out exp2 --scenes scenes/some.glb --sim-seed 5 --methods plain --no-baseline-pose-refine" + tiny,
      out);
  REQUIRE(rc == 0);
  CHECK(slurp(dir / "exp2" / "some" / "plain" / "config.json").find("\"pose_refine\": false") != std::string::npos);
  // A scene file without --sim-seed, and a name that is neither, are refused.
  CHECK(run_evflow(dir, "experiment --out bad --scenes scenes/some.glb --blur-px 4", out) != 0);
  CHECK(out.find("--sim-seed") != std::string::npos);
  CHECK(!fs::exists(dir / "bad" / "some"));
  fs::remove_all(dir);
}
