// Faults a run survives: `kill -9` while training (then --resume), and a full disk (a file-size
// limit) while saving a checkpoint, exporting or simulating.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_helpers.h"
#include "gpu_fixture.h"
#include "train/checkpoint.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;
using Catch::Contains;

extern char** environ;

namespace {

const std::string kSim = "simulate --scene gallery --out data --width 32 --height 24 --blur-px 3";
const std::string kKeys =
    " init_gaussians=300 max_gaussians=600 sh_degree=1 virtual_frames=2 method=blur-only checkpoint_every=1 "
    "log_every=1";
const std::string kTrain = " iterations=150" + kKeys;

// Starts `evflow train data --out RUN ...` in `dir`, output to RUN.log; returns its process id.
pid_t spawn_train(const fs::path& dir, const std::string& run, bool resume) {
  std::vector<std::string> args = {evflow_binary().string(), "train", (dir / "data").string(), "--out",
                                   (dir / run).string()};
  if (resume) args.push_back("--resume");
  std::istringstream keys(kTrain);
  for (std::string k; keys >> k;) args.push_back(k);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  const std::string log = (dir / (run + ".log")).string();
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  REQUIRE(rc == 0);
  return pid;
}

// The step of RUN's checkpoint, 0 when there is none yet.
uint32_t checkpoint_step(const fs::path& run) {
  try {
    return read_checkpoint(run / "checkpoint.ckpt").step;
  } catch (const std::exception&) { return 0; }
}

// Waits until RUN's checkpoint is past `step`, then kills the run with SIGKILL after `delay_ms`.
// Returns false when the run ended by itself first.
bool kill_after(pid_t pid, const fs::path& run, uint32_t step, int delay_ms) {
  int status = 0;
  for (int i = 0; i < 6000 && checkpoint_step(run) <= step; ++i) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

// Runs `evflow ARGS` in `dir` under a file-size limit of `blocks` (sh's ulimit -f units).
int run_limited(const fs::path& dir, int blocks, const std::string& args, std::string& out) {
  const std::string cmd = "cd " + quote(dir.string()) + " && ulimit -f " + std::to_string(blocks) + " && " +
                          quote(evflow_binary().string()) + " " + args + " > limited.log 2>&1";
  const int status = std::system(cmd.c_str());
  out = slurp(dir / "limited.log");
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Every file under `dir` (relative path -> bytes).
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = slurp(e.path());
  return files;
}

size_t hidden_files(const fs::path& dir) {
  size_t n = 0;
  for (auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string()[0] == '.') ++n;
  return n;
}

}  // namespace

TEST_CASE("faults: kill -9 while training, then --resume: the final checkpoint equals an uninterrupted run's",
          "[faults][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_fault_kill");
  std::string out;
  REQUIRE(run_evflow(dir, kSim + " --seed 4", out) == 0);
  REQUIRE(run_evflow(dir, "train data --out ref" + kTrain, out) == 0);
  std::mt19937 rng(std::random_device{}());
  uint32_t step = 0;
  for (int kill = 0; kill < 3; ++kill) {
    const int delay = int(rng() % 300);
    INFO("kill " << kill << " at " << delay << " ms after checkpoint step " << step + 1);
    const pid_t pid = spawn_train(dir, "killed", kill > 0);
    REQUIRE(kill_after(pid, dir / "killed", step, delay));
    const uint32_t saved = checkpoint_step(dir / "killed");
    REQUIRE(saved > step);
    step = saved;
    std::printf("faults: kill -9 %d ms after a checkpoint; the last whole checkpoint is step %u\n", delay, step);
  }
  REQUIRE(step < 150);
  REQUIRE(run_evflow(dir, "train data --out killed --resume" + kTrain, out) == 0);
  if (test::bit_reproducible()) {
    REQUIRE(slurp(dir / "killed" / "checkpoint.ckpt") == slurp(dir / "ref" / "checkpoint.ckpt"));
  } else {  // a GPU's float adds come in any order: the same step, the same splats to 1e-3
    const Checkpoint k = read_checkpoint(dir / "killed" / "checkpoint.ckpt");
    const Checkpoint r = read_checkpoint(dir / "ref" / "checkpoint.ckpt");
    REQUIRE(k.step == r.step);
    REQUIRE(test::same_values(k.cloud.means, r.cloud.means, 1e-3));
    REQUIRE(test::same_values(k.cloud.sh, r.cloud.sh, 1e-3));
  }
  CHECK(hidden_files(dir / "killed") == 0);  // no temporary checkpoint left behind
  // curve.csv: every step once, in order, every row whole.
  std::istringstream curve(slurp(dir / "killed" / "curve.csv"));
  std::string line;
  std::getline(curve, line);
  for (uint32_t s = 1; s <= 150; ++s) {
    REQUIRE(std::getline(curve, line));
    INFO("curve.csv row " << s << ": " << line);
    REQUIRE(line.rfind(std::to_string(s) + ",", 0) == 0);
  }
  REQUIRE(!std::getline(curve, line));
  fs::remove_all(dir);
}

TEST_CASE("faults: a full disk while saving a checkpoint, exporting or simulating: a clear error, old files kept",
          "[faults][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_fault_disk");
  std::string out;
  REQUIRE(run_evflow(dir, kSim + " --seed 4", out) == 0);
  REQUIRE(run_evflow(dir, "train data --out run iterations=2" + kKeys, out) == 0);
  REQUIRE(run_evflow(dir, "export run --ply s.ply --gltf s.glb", out) == 0);
  const std::string ckpt = slurp(dir / "run" / "checkpoint.ckpt"), ply = slurp(dir / "s.ply"),
                    glb = slurp(dir / "s.glb");
  const auto dataset = snapshot(dir / "data");
  REQUIRE(ckpt.size() > 40 * 1024);
  // 16 blocks: at most 16 KiB (bash) or 8 KiB (dash); the checkpoint, the exports and the
  // simulated dataset are all larger.
  int rc = run_limited(dir, 16, "train data --out run --resume iterations=3" + kKeys, out);
  INFO(out);
  CHECK(rc == 1);
  CHECK_THAT(out, Contains("checkpoint.ckpt: write failed (File too large)"));
  CHECK(slurp(dir / "run" / "checkpoint.ckpt") == ckpt);
  rc = run_limited(dir, 16, "export run --ply s.ply --gltf s.glb", out);
  CHECK(rc == 1);
  CHECK_THAT(out, Contains("s.") && Contains("File too large"));
  CHECK(slurp(dir / "s.ply") == ply);
  CHECK(slurp(dir / "s.glb") == glb);
  rc = run_limited(dir, 16, kSim + " --seed 5", out);
  CHECK(rc == 1);
  CHECK_THAT(out, Contains("data not written (kept as it was)") && Contains("File too large"));
  CHECK(snapshot(dir / "data") == dataset);
  CHECK(hidden_files(dir) == 0);  // no temporary file or folder left behind
  // Without the limit the same commands succeed (so the limit was the cause).
  REQUIRE(run_evflow(dir, kSim + " --seed 5", out) == 0);
  CHECK(snapshot(dir / "data") != dataset);
  fs::remove_all(dir);
}

TEST_CASE("faults: --resume with other loss terms than the run's is refused before a step, leaving the run as it was",
          "[faults][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_fault_terms");
  std::string out;
  REQUIRE(run_evflow(dir, kSim + " --seed 5", out) == 0);
  REQUIRE(run_evflow(dir, "train data --out run iterations=3" + kKeys, out) == 0);
  const std::string config = slurp(dir / "run" / "config.json"), ckpt = slurp(dir / "run" / "checkpoint.ckpt");
  // blur+events adds the event term's column to blur-only's.
  REQUIRE(run_evflow(dir, "train data --out run --resume iterations=6" + kKeys + " method=blur+events", out) != 0);
  CHECK_THAT(out, Contains("curve.csv") && Contains("are not this run's loss terms"));
  CHECK(slurp(dir / "run" / "config.json") == config);
  CHECK(slurp(dir / "run" / "checkpoint.ckpt") == ckpt);
  // The run's own keys still continue it.
  REQUIRE(run_evflow(dir, "train data --out run --resume iterations=6" + kKeys, out) == 0);
  CHECK(checkpoint_step(dir / "run") == 6);
}
