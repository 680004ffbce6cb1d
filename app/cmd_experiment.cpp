// evflow experiment: the deblurring comparison of the paper's configurations on simulated scenes
// (with --ablation: the paper's ablation rows, and their table in DIR/ablation.md).
// For every scene: simulate (unless its dataset exists), then train and evaluate every method
// (plain, edi, blur-only, blur+events; blur+events+warp on request) with the same preset and overrides, and write one
// table (DIR/experiment.md, DIR/experiment.json). Each run is a separate `evflow train` / `evflow eval` process; a run
// whose eval.json exists is reused, so an interrupted experiment continues. The same runs can go to a batch scheduler
// instead: --emit-jobs writes one command line per (scene, method) (`evflow experiment --job ...`), --collect builds
// the table once they are done.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "ablation_table.h"
#include "cli.h"
#include "experiment_plan.h"
#include "io/atomic_file.h"

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

double run_command(const std::string& cmd, const fs::path& log) {
  const auto t0 = std::chrono::steady_clock::now();
  std::printf("  $ %s\n", cmd.c_str());
  std::fflush(stdout);
  fs::create_directories(log.parent_path());
  const int rc = std::system((cmd + " >> " + shell_quote(log.string()) + " 2>&1").c_str());
  if (rc != 0)
    throw std::runtime_error("command failed (exit " + std::to_string(rc) + "), see " + log.string() + ": " + cmd);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A dataset folder made by `command(tmp)` unless it holds dataset.json: into a fresh folder that
// is then renamed into place, so jobs of one scene running at the same time never read half a
// dataset (the first rename wins; the other copies, identical, are dropped).
void ensure_dataset(const fs::path& data, const std::string& label, const fs::path& log,
                    const std::function<std::string(const fs::path&)>& command) {
  if (fs::exists(data / "dataset.json")) return;
  char host[256] = "host";
  gethostname(host, sizeof host - 1);
  const fs::path tmp = data.string() + ".partial-" + host + "-" + std::to_string(getpid());
  std::printf("%s\n", label.c_str());
  fs::remove_all(tmp);
  run_command(command(tmp), log);
  std::error_code ec;
  fs::rename(tmp, data, ec);
  if (ec) {
    fs::remove_all(tmp);
    if (!fs::exists(data / "dataset.json"))
      throw std::runtime_error(data.string() + ": cannot move the dataset into place: " + ec.message());
  }
}

// A scene's simulated data and, with --poses colmap, their COLMAP-posed copy.
void ensure_data(const ExperimentPlan& plan, size_t si, const std::string& self, const fs::path& log) {
  const std::string scene = "[" + plan.scenes[si].label + "] ";
  ensure_dataset(plan.data_dir(si), scene + "simulate", log,
                 [&](const fs::path& tmp) { return plan.simulate_command(self, si, tmp); });
  if (plan.poses == "colmap")
    ensure_dataset(plan.train_data_dir(si), scene + "poses (COLMAP)", log,
                   [&](const fs::path& tmp) { return plan.poses_command(self, si, tmp); });
}

// One (scene, method) run: trained and evaluated unless its eval.json exists; its training time
// goes to train_seconds.txt.
void run_one(const ExperimentPlan& plan, size_t si, const std::string& m, const std::string& self,
             const fs::path& log) {
  const fs::path run = plan.run_dir(si, m);
  if (fs::exists(run / "eval.json")) return;
  std::printf("[%s] %s\n", plan.scenes[si].label.c_str(), m.c_str());
  const double secs = run_command(plan.train_command(self, si, m), log);
  run_command(plan.eval_command(self, si, m), log);
  io::write_file_atomic(run / "train_seconds.txt", [&](const fs::path& tmp) { std::ofstream(tmp) << secs << "\n"; });
}

// A finished run's row of the table (its eval.json and train_seconds.txt).
nlohmann::json table_row(const ExperimentPlan& plan, size_t si, const std::string& m) {
  const fs::path run = plan.run_dir(si, m);
  double secs = -1;
  if (fs::exists(run / "train_seconds.txt")) std::ifstream(run / "train_seconds.txt") >> secs;
  double blur_px = 0;
  try {
    blur_px = std::stod(plan.scenes[si].blur_px);
  } catch (const std::exception&) {
    throw std::runtime_error("experiment_plan.json: scene " + plan.scenes[si].label + "'s blur_px '" +
                             plan.scenes[si].blur_px + "' is not a number");
  }
  std::ifstream f(run / "eval.json");
  try {
    nlohmann::json e;
    f >> e;
    auto get = [&](const char* set, const char* key) {
      return e.contains(set) ? e.at(set).at(key).get<double>() : std::nan("");
    };
    return {{"scene", plan.scenes[si].label},
            {"blur_px", blur_px},
            {"method", m},
            {"deblur_psnr", get("deblur", "mean_psnr")},
            {"deblur_ssim", get("deblur", "mean_ssim")},
            {"novel_psnr", get("novel", "mean_psnr")},
            {"novel_ssim", get("novel", "mean_ssim")},
            {"novel_refined_psnr", get("novel_refined", "mean_psnr")},
            {"train_seconds", secs}};
  } catch (const std::exception& ex) { throw std::runtime_error((run / "eval.json").string() + ": " + ex.what()); }
}

std::string markdown_row(const nlohmann::json& row, const std::string& blur_px) {
  char line[320];
  std::snprintf(line, sizeof line, "| %s | %s | %s | %.2f | %.4f | %.2f | %.4f | %.2f | %.0f |\n",
                row["scene"].get<std::string>().c_str(), blur_px.c_str(), row["method"].get<std::string>().c_str(),
                row["deblur_psnr"].get<double>(), row["deblur_ssim"].get<double>(), row["novel_psnr"].get<double>(),
                row["novel_ssim"].get<double>(), row["novel_refined_psnr"].get<double>(),
                row["train_seconds"].get<double>());
  return line;
}

// DIR/experiment.md and DIR/experiment.json from the plan's finished runs, in plan order;
// `missing` gets the run folders without an eval.json. Returns the markdown table.
std::string write_table(const ExperimentPlan& plan, std::vector<std::string>& missing) {
  std::string md =
      "| scene | blur px | method | deblur PSNR | deblur SSIM | novel PSNR | novel SSIM | novel PSNR (refined) | "
      "train s |\n|---|---|---|---|---|---|---|---|---|\n";
  nlohmann::json table = nlohmann::json::array();
  for (size_t si = 0; si < plan.scenes.size(); ++si)
    for (const auto& m : plan.methods) {
      if (!fs::exists(plan.run_dir(si, m) / "eval.json")) {
        missing.push_back(plan.run_dir(si, m).string());
        continue;
      }
      table.push_back(table_row(plan, si, m));
      md += markdown_row(table.back(), plan.scenes[si].blur_px);
    }
  const nlohmann::json j = {{"preset", plan.preset},
                            {"overrides", plan.overrides},
                            {"width", plan.width},
                            {"height", plan.height},
                            {"pose_noise_rot_deg", std::stod(plan.noise_rot)},
                            {"pose_noise_trans", std::stod(plan.noise_trans)},
                            {"baseline_pose_refine", plan.baseline_pose_refine},
                            {"poses", plan.poses},
                            {"runs", table}};
  io::write_file_atomic(plan.out / "experiment.md", [&](const fs::path& tmp) { std::ofstream(tmp) << md; });
  io::write_file_atomic(plan.out / "experiment.json",
                        [&](const fs::path& tmp) { std::ofstream(tmp) << j.dump(2) << "\n"; });
  if (plan.ablation)
    io::write_file_atomic(plan.out / "ablation.md",
                          [&](const fs::path& tmp) { std::ofstream(tmp) << ablation_markdown(table); });
  return md;
}

}  // namespace

static int collect(const fs::path& dir) {
  const ExperimentPlan plan = ExperimentPlan::read(dir);
  std::vector<std::string> missing;
  const std::string md = write_table(plan, missing);
  std::printf("%s", md.c_str());
  if (missing.empty()) return 0;
  std::fprintf(stderr, "evflow experiment: %zu of %zu runs have not finished (no eval.json):\n", missing.size(),
               plan.scenes.size() * plan.methods.size());
  for (const auto& m : missing) std::fprintf(stderr, "  %s\n", m.c_str());
  return 1;
}

static void emit_jobs(const ExperimentPlan& plan, const std::string& self, const fs::path& file) {
  plan.write();
  std::string lines;
  for (size_t si = 0; si < plan.scenes.size(); ++si)
    for (const auto& m : plan.methods) lines += plan.job_line(self, si, m) + "\n";
  io::write_file_atomic(file, [&](const fs::path& tmp) { std::ofstream(tmp) << lines; });
  std::printf("wrote %s (%zu jobs) and %s\n", file.c_str(), plan.scenes.size() * plan.methods.size(),
              (plan.out / "experiment_plan.json").c_str());
}

static int run_experiment(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf("%s", ExperimentPlan::help().c_str());
    return 0;
  }
  const std::string collect_dir = p.value("--collect");
  if (!collect_dir.empty()) {
    p.reject_unknown();
    if (!p.positional().empty()) throw std::invalid_argument("--collect DIR takes no other arguments");
    return collect(collect_dir);
  }
  const std::string jobs_file = p.value("--emit-jobs");
  const bool job = p.flag("--job");
  const ExperimentPlan plan = ExperimentPlan::from_args(p);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  if (!jobs_file.empty()) {
    emit_jobs(plan, self, jobs_file);
    return 0;
  }
  if (job) {  // one line of --emit-jobs: its runs, each logged beside its folder; no table
    for (size_t si = 0; si < plan.scenes.size(); ++si)
      for (const auto& m : plan.methods) {
        const fs::path log = plan.run_dir(si, m).string() + ".log";
        ensure_data(plan, si, self, log);
        run_one(plan, si, m, self, log);
      }
    return 0;
  }
  plan.write();
  const fs::path log = plan.out / "experiment.log";
  std::string md;
  for (size_t si = 0; si < plan.scenes.size(); ++si) {
    ensure_data(plan, si, self, log);
    for (const auto& m : plan.methods) {
      run_one(plan, si, m, self, log);
      std::vector<std::string> missing;
      md = write_table(plan, missing);  // after every run, so a partial experiment has its table too
    }
  }
  std::printf("\n%s", md.c_str());
  return 0;
}

static Command reg("experiment",
                   "train and score plain / edi / blur-only / blur+events on simulated scenes (one table)",
                   run_experiment);

}  // namespace evflow::app
