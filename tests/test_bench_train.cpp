// evflow bench train: the step's split and the run's peak memory as JSON.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "bench_stats.h"
#include "cli_helpers.h"

using namespace evflow::test;
namespace fs = std::filesystem;

// The benches' median is a time one run took: for an even count the upper middle value.
TEST_CASE("bench: the printed median of an even count is the upper middle value", "[cli]") {
  CHECK(evflow::app::median({}) == 0.0);
  CHECK(evflow::app::median({7.0}) == 7.0);
  CHECK(evflow::app::median({3.0, 1.0, 2.0}) == 2.0);
  CHECK(evflow::app::median({4.0, 1.0, 3.0, 2.0}) == 3.0);
  CHECK(evflow::app::median({10.0, 20.0}) == 20.0);
}

TEST_CASE("bench train: JSON with it/s, the split of a step and the peak host and device memory", "[cli]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_bench_train");
  std::string out;
  REQUIRE(run_evflow(dir, "bench train --width 64 --height 48 --gaussians 2000 --steps 2 --views 2 --json", out) == 0);
  const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
  CHECK(b["gaussians"] == 2000);
  CHECK(b["it_per_s"].get<double>() > 0);
  CHECK(b["ms"]["step"].get<double>() > 0);
  // The Gaussians' parameters, gradients and Adam moments alone need 2000 x 59 floats x 4 x 4 bytes.
  const double device = b["peak_device_mib"].get<double>(), host = b["peak_host_mib"].get<double>();
  CHECK(device > 2000.0 * 59 * 4 * 4 / (1 << 20));
  CHECK(device < 512);
  // On a CPU driver the buffers live in the process's memory.
  if (b["device"].get<std::string>().find("llvmpipe") != std::string::npos) CHECK(host > device);
}

// --kernels: each kernel's GPU time per step, slowest first, and its dispatches per step.
TEST_CASE("bench train: --kernels lists every kernel of a step with its time and dispatches", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_kernels");
  std::string out;
  REQUIRE(run_evflow(dir, "bench train --width 64 --height 48 --gaussians 2000 --steps 2 --views 2 --kernels --json",
                     out) == 0);
  const nlohmann::ordered_json b = nlohmann::ordered_json::parse(out.substr(out.find('{')));  // in printed order
  const nlohmann::ordered_json& ms = b.at("kernels_ms");
  const nlohmann::ordered_json& n = b.at("kernel_dispatches");
  REQUIRE(ms.size() == n.size());
  // A plain step: one render and its backward, the image terms and Adam (kernels every device
  // runs; the compositing's builds differ, and the block path finds its tile ranges itself).
  for (const char* k : {"splat/project", "splat/pose_reduce", "optim/adam"}) {
    INFO(k);
    REQUIRE(ms.contains(k));
    CHECK(ms[k].get<double>() >= 0.0);
    CHECK(n[k].get<double>() >= 1.0);
  }
  int compositing = 0;  // forward and backward, whichever builds
  for (auto it = ms.begin(); it != ms.end(); ++it) compositing += it.key().rfind("splat/rasterize", 0) == 0;
  CHECK(compositing == 2);
  CHECK(n["splat/project"].get<double>() == 1.0);  // one render a step
  double previous = 1e300, sum = 0;
  for (auto it = ms.begin(); it != ms.end(); ++it) {  // printed slowest first
    CHECK(it.value().get<double>() <= previous);
    previous = it.value().get<double>();
    sum += previous;
  }
  // The kernels ran inside the step's wall time (medians of each, so only roughly).
  CHECK(sum <= 2.0 * b["ms"]["step"].get<double>());
  // Without the flag, none.
  REQUIRE(run_evflow(dir, "bench train --width 64 --height 48 --gaussians 2000 --steps 2 --views 2 --json", out) == 0);
  CHECK_FALSE(nlohmann::json::parse(out.substr(out.find('{'))).contains("kernels_ms"));
}

// The host's round trips per step, as a GPU pays them (EVF_STAGED=1: every copy staged): the
// batch's intersection counts come back in one download, every loss term's value in another.
TEST_CASE("bench train: a blur+events step's round trips do not grow with its frames or terms", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_round_trips");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 2",
                     out) == 0);
  setenv("EVF_STAGED", "1", 1);
  const int rc = run_evflow(
      dir, "bench train --data sim --method blur+events --gaussians 500 --steps 2 --json event_flip_until=0", out);
  unsetenv("EVF_STAGED");
  REQUIRE(rc == 0);
  const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
  // The counts, the loss values and the trajectory's pose gradients: one download each.
  CHECK(b["transfers_per_step"].get<double>() == 3.0);
  CHECK(b["submits_per_step"].get<double>() <= 12.0);
}

// The direction check's reversed score rides in the step's loss submit, and the two scores come
// back after it in one download: with EVF_STAGED=1 (each download a submit of its own, as on a
// GPU) the check adds one round trip to a blur+events step, that download. One untimed step per
// view first: buffers that grow on a view's first visit (and, with EVF_POISON, are filled by a
// submit of their own) are all in place before the timed steps.
TEST_CASE("bench train: the direction check adds one round trip to a step, its scores' download", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_check_submits");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 2",
                     out) == 0);
  auto submits = [&](const std::string& until) {
    setenv("EVF_STAGED", "1", 1);
    const int rc = run_evflow(dir,
                              "bench train --data sim --method blur+events --gaussians 500 --steps 2 --warmup 2 --json "
                              "event_flip_until=" +
                                  until,
                              out);
    unsetenv("EVF_STAGED");
    REQUIRE(rc == 0);
    const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
    return std::make_pair(b["submits_per_step"].get<double>(), b["transfers_per_step"].get<double>());
  };
  const auto off = submits("0"), on = submits("1");
  INFO("check off: " << off.first << " submits, " << off.second << " copies; on: " << on.first << ", " << on.second);
  CHECK(on.first == off.first + 1);
  CHECK(on.second == off.second + 1);
}

// --warmup: untimed steps first. One per training view reaches a run's steady state, where every
// view's event counts are kept and no timed step counts events again.
TEST_CASE("bench train --warmup: one untimed step per view leaves no event counting to the timed steps", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_warmup");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 3",
                     out) == 0);
  auto counts = [&](int warmup) {
    REQUIRE(run_evflow(dir,
                       "bench train --data sim --method blur+events --gaussians 500 --steps 3 --json --warmup " +
                           std::to_string(warmup),
                       out) == 0);
    const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
    CHECK(b["warmup"] == warmup);
    return b["event_counts_per_step"].get<double>();
  };
  // Three views, visited in a shuffled order each epoch: after one untimed step the next two
  // steps count their views' events for the first time.
  CHECK(counts(1) > 0.5);
  CHECK(counts(3) == 0.0);
}

// The loss stage's GPU time by term: the image model's forward and backward, each term under its
// name and the frames' shares of the image terms' gradient, together no longer than the stage.
// The direction check (on in every timed step) has no stage of its own: the event term sums the
// reversed order in its own passes. One timed step, since each figure is a median over the
// steps: with two, each is the larger of its two values, and their sum may exceed the larger of
// the two steps' wall times.
TEST_CASE("bench train: the loss terms' stage times by name", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_loss_stages");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 2",
                     out) == 0);
  const char* const names[] = {"image model", "l1_ssim", "frame shares", "events", "render gradients"};
  for (const char* until : {"1", "0"}) {
    REQUIRE(run_evflow(dir,
                       std::string("bench train --data sim --method blur+events --gaussians 500 --steps 1 --json "
                                   "event_flip_until=") +
                           until,
                       out) == 0);
    const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
    const nlohmann::json& stages = b["loss_stages_ms"];
    INFO("event_flip_until=" << until << ": " << stages.dump());
    double sum = 0;
    for (const char* name : names) {
      REQUIRE(stages.contains(name));
      CHECK(stages[name].get<double>() > 0);
      sum += stages[name].get<double>();
    }
    CHECK(stages.size() == 5);
    CHECK(sum <= b["ms"]["loss"].get<double>());
  }
}

// --splats: the steps start from a run's Gaussians (their count, not --gaussians) and, in blur
// mode, its learned exposures; a missing run is named.
TEST_CASE("bench train --splats: steps from a run's Gaussians", "[cli]") {
  const fs::path dir = fresh_dir("evflow_bench_splats");
  std::string out;
  REQUIRE(run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 3 --train-views 2",
                     out) == 0);
  REQUIRE(run_evflow(dir, "train sim --out run method=blur-only iterations=3 init_gaussians=300 densify=false", out) ==
          0);
  REQUIRE(run_evflow(dir, "bench train --data sim --method blur-only --splats run --gaussians 900 --steps 2 --json",
                     out) == 0);
  const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
  CHECK(b["gaussians"] == 300);
  CHECK(b["it_per_s"].get<double>() > 0);
  REQUIRE(run_evflow(dir, "export run --ply splats.ply", out) == 0);
  REQUIRE(run_evflow(dir, "bench train --data sim --method blur-only --splats splats.ply --steps 2 --json", out) == 0);
  CHECK(nlohmann::json::parse(out.substr(out.find('{')))["gaussians"] == 300);
  CHECK(run_evflow(dir, "bench train --data sim --splats nowhere --steps 2", out) != 0);
  CHECK(out.find("nowhere") != std::string::npos);
}
