// What `evflow experiment` runs: the scenes (each with its folder, simulation seed and blur), the
// methods, the preset and overrides, and the command lines of each step. Written to
// DIR/experiment_plan.json by a direct run and by --emit-jobs; --collect reads it back.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli.h"

namespace evflow::app {

struct ExperimentScene {
  std::string scene;  // a built-in scene's name, or a scene file's absolute path
  std::string label;  // its folder under DIR: the name, or the file's stem
  std::string seed;   // its simulation seed
  std::string blur_px;
};

struct ExperimentPlan {
  std::filesystem::path out;  // DIR, absolute
  std::vector<ExperimentScene> scenes;
  std::vector<std::string> methods;
  std::string width = "173", height = "130", preset = "fast", refine_iters = "30";
  std::string noise_rot = "0.4", noise_trans = "0.01";
  std::string poses = "perturbed";     // or "colmap": train on `evflow poses` of the simulated data
  std::string sim_seed;                // "" when every scene has its own
  std::vector<std::string> sim_seeds;  // --sim-seeds: every scene once per seed, in DIR/<scene>-s<seed>/
  bool ablation = false;               // the methods are the ablation's rows; DIR/ablation.md too
  std::string shake = "smooth";        // the simulator's --shake: smooth or jerk
  std::string device;                  // passed on to every step ("" : the default device)
  bool baseline_pose_refine = true;
  std::vector<std::string> overrides;  // key=value for every run

  // From the command line (the options of `evflow experiment --help`); refuses unknown scenes
  // and methods, bad seeds and overrides before any work.
  static ExperimentPlan from_args(ArgParser& p);
  static std::string help();
  nlohmann::json to_json() const;
  // DIR/experiment_plan.json; throws naming the file when it is missing or malformed.
  static ExperimentPlan read(const std::filesystem::path& dir);
  void write() const;

  std::filesystem::path data_dir(size_t scene) const { return out / scenes[scene].label / "data"; }
  // What the methods train on: the simulated data, or their COLMAP-posed copy.
  std::filesystem::path train_data_dir(size_t scene) const {
    return poses == "colmap" ? out / scenes[scene].label / "data_colmap" : data_dir(scene);
  }
  std::filesystem::path run_dir(size_t scene, const std::string& method) const {
    return poses == "colmap" ? out / scenes[scene].label / "colmap" / method : out / scenes[scene].label / method;
  }
  // The steps' command lines, `self` being the evflow binary.
  std::string simulate_command(const std::string& self, size_t scene, const std::filesystem::path& data) const;
  std::string poses_command(const std::string& self, size_t scene, const std::filesystem::path& out) const;
  std::string train_command(const std::string& self, size_t scene, const std::string& method) const;
  std::string eval_command(const std::string& self, size_t scene, const std::string& method) const;
  // One self-contained line that does one (scene, method) run: `evflow experiment --job ...`.
  std::string job_line(const std::string& self, size_t scene, const std::string& method) const;
};

// Single-quoted for sh.
std::string shell_quote(const std::string& s);

}  // namespace evflow::app
