// Command-line values that used to crash or hang the program: each is refused by name, before
// anything runs or is written.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_helpers.h"
#include "sim/flow_truth.h"

using namespace evflow::test;
namespace fs = std::filesystem;

namespace {

// `args` exits with status 1 (not a signal, not a timeout) and says `message`.
void refused(const fs::path& dir, const std::string& args, const std::string& message) {
  std::string out;
  INFO(args);
  CHECK(run_evflow(dir, args, out) == 1);
  INFO(out);
  CHECK(out.find(message) != std::string::npos);
}

}  // namespace

TEST_CASE("command line: out-of-range values and repeated or empty options are refused by name", "[cli]") {
  const fs::path dir = fresh_dir("evflow_cli_args");
  // Counts read as unsigned: -1 was 4 billion frames or refinement steps, 0 repeats an empty median.
  refused(dir, "bench raster --width 32 --height 24 --gaussians 100 --repeats 0 --json", "--repeats must be 1..");
  refused(dir, "bench raster --width 32 --height 24 --gaussians 100 --warmup -1 --json", "--warmup must be 0..");
  refused(dir, "render nowhere.ply --out r --frames -1", "--frames must be 1..");
  refused(dir, "render nowhere.ply --out r --sh-degree 9", "--sh-degree must be -1..3");
  refused(dir, "eval nowhere --refine-iters -1", "--refine-iters must be 0..");
  refused(dir, "eval nowhere --refine-iters 5x", "--refine-iters expects an integer, got '5x'");
  refused(dir, "train nowhere --out r virtual_frames=50000", "config key 'virtual_frames' must be 0..32");
  refused(dir, "simulate --out s --arc nan", "--arc expects a finite number, got 'nan'");
  // Image sizes are read by one helper in every command; the viewer's smallest window is 16 px.
  refused(dir, "render nowhere.ply --out r --height 0", "--height must be 1..16384, got 0");
  refused(dir, "view nowhere.ply --width 8", "--width must be 16..16384, got 8");
  // fit-demo took any number: --views 0 crashed (a signal), --gaussians -1 was a library's
  // allocation error, --width 0 an error from the renderer.
  refused(dir, "fit-demo --out f --views 0", "--views must be 1..1000, got 0");
  refused(dir, "fit-demo --out f --gaussians -1", "--gaussians must be 1..");
  refused(dir, "fit-demo --out f --width 0", "--width must be 1..16384, got 0");
  // A negative warm-up count ran the whole benchmark.
  refused(dir, "bench conv --warmup -1", "--warmup must be 0..");
  refused(dir, "poses nowhere --threads -3", "--threads must be 0..4096, got -3");
  // Both were left to the simulator, which refused them only after the header line.
  refused(dir, "simulate --out s --train-views -1", "--train-views must be 1..100000, got -1");
  refused(dir, "simulate --out s --max-subframes 0", "--max-subframes must be 1..1000000, got 0");
  // NaN passed every config key's parse and every range check written as `x < lo || x > hi`.
  refused(dir, "train nowhere --out r event_weight=nan", "config key 'event_weight' expects a finite number");
  // The second value used to be reported as an unknown option.
  refused(dir, "bench raster --gaussians 1 --gaussians 2", "--gaussians is given twice");
  // An empty value (an unset shell variable) used to read as the option left out: a whole
  // experiment ran instead of writing its job lines.
  refused(dir, "experiment --out e --scenes default --emit-jobs ''",
          "--emit-jobs needs a value, and the one given is empty");
  // The job lines would each have hung in eval.
  refused(dir, "experiment --out e --scenes default --refine-iters -5 --emit-jobs j.txt",
          "--refine-iters needs a whole number in 0..");
  refused(dir, "experiment --out e --scenes default --pose-noise-rot x --emit-jobs j.txt", "--pose-noise-rot needs");
  // Errors that named a library call or no file.
  refused(dir, "devices --device 99999999999999999999", "--device 99999999999999999999: only");
  std::ofstream(dir / "bad.json") << R"({"preset": 5})";
  refused(dir, "train nowhere --out r --config bad.json", "bad.json: ");
  refused(dir, "train bad.json --out r", "bad.json: is a file, and a dataset is a folder");
  CHECK_FALSE(fs::exists(dir / "e"));
  CHECK_FALSE(fs::exists(dir / "j.txt"));
  CHECK_FALSE(fs::exists(dir / "s"));
  CHECK_FALSE(fs::exists(dir / "f"));
}

TEST_CASE("experiment --collect: a run's eval.json of the wrong shape is named", "[cli][experiment]") {
  const fs::path dir = fresh_dir("evflow_collect_bad");
  std::string out;
  REQUIRE(run_evflow(dir, "experiment --out x --scenes default --methods plain --emit-jobs jobs.txt", out) == 0);
  fs::create_directories(dir / "x" / "default" / "plain");
  std::ofstream(dir / "x" / "default" / "plain" / "eval.json") << R"({"deblur": {"mean_psnr": "high"}})";
  refused(dir, "experiment --collect x", (dir / "x" / "default" / "plain" / "eval.json").string() + ": ");
}

TEST_CASE("ground-truth flow: too few subframes and a camera of another size are named", "[cli][flow]") {
  const fs::path dir = fresh_dir("evflow_gt_flow_bad");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 2",
                     out) == 0);
  const fs::path traj = dir / "sim" / "gt" / "trajectories.json";
  nlohmann::json j = nlohmann::json::parse(slurp(traj));
  const std::string view = j["train"][0]["name"];
  REQUIRE(evflow::sim::ground_truth_interval_flow(dir / "sim", view, {0.0, 0.5, 1.0}).has_value());
  j["train"][0]["subframes"] = nlohmann::json::array({j["train"][0]["subframes"][0]});
  std::ofstream(traj) << j.dump();
  try {
    evflow::sim::ground_truth_interval_flow(dir / "sim", view, {0.0, 0.5, 1.0});
    FAIL("one subframe accepted");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find(traj.string() + ": view '" + view + "' has 1 subframes") != std::string::npos);
  }
  // A truth of 4 pixels against a sensor of 768 used to read past its end.
  const std::vector<float> truth(8, 0.0f), estimate(2 * 768, 0.0f);
  const std::vector<uint32_t> counts(768, 1);
  CHECK_THROWS_WITH(evflow::sim::endpoint_error(estimate, truth, counts),
                    Catch::Contains("has 4 pixels, the estimate 768 and the sensor 768"));
}
