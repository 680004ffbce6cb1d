#include "experiment_plan.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "ablation_table.h"
#include "io/atomic_file.h"
#include "sim/builtin_scenes.h"
#include "train/train_config.h"

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// A built-in scene's simulation seed: its place in sim::builtin_scene_names(), from 1.
std::string builtin_scene_seed(size_t index) { return std::to_string(index + 1); }

// --blur-px, once a single value is spread over the scenes, holds one value per scene.
void require_blur_per_scene(const std::vector<std::string>& scenes, const std::vector<std::string>& blur) {
  if (blur.size() != scenes.size())
    throw std::invalid_argument("--blur-px needs one value per scene (" + std::to_string(scenes.size()) + ")");
}

// The settings are kept as text for the job lines; each must read as what the subcommand it is
// passed to expects (digits only where `integer`), within [lo, hi], before any job runs.
void require_number(const std::string& option, const std::string& v, double lo, double hi, bool integer = false) {
  size_t pos = 0;
  double x = 0;
  try {
    x = std::stod(v, &pos);
  } catch (...) { pos = 0; }
  if (pos == 0 || pos != v.size() || !std::isfinite(x) || x < lo || x > hi ||
      (integer && v.find_first_not_of("0123456789") != std::string::npos)) {
    char range[64];
    std::snprintf(range, sizeof range, "%g..%g", lo, hi);
    throw std::invalid_argument(option + " needs " + (integer ? "a whole number" : "a number") + " in " + range +
                                ", got '" + v + "'");
  }
}

// The scenes of --scenes with their folders and seeds; unknown scenes are refused here.
std::vector<ExperimentScene> resolve_scenes(const std::vector<std::string>& scenes,
                                            const std::vector<std::string>& blur, const std::string& sim_seed);

// With --sim-seeds: every scene once per seed, its folder named <scene>-s<seed>.
std::vector<ExperimentScene> resolve_scenes(const std::vector<std::string>& scenes,
                                            const std::vector<std::string>& blur,
                                            const std::vector<std::string>& seeds) {
  require_blur_per_scene(scenes, blur);
  std::vector<ExperimentScene> out;
  for (size_t i = 0; i < scenes.size(); ++i)
    for (const std::string& seed : seeds) {
      ExperimentScene s = resolve_scenes({scenes[i]}, {blur[i]}, seed).front();
      s.label += "-s" + seed;
      for (const auto& o : out)
        if (o.label == s.label)
          throw std::invalid_argument("experiment: two scenes would share the folder '" + s.label + "'");
      out.push_back(s);
    }
  return out;
}

std::vector<ExperimentScene> resolve_scenes(const std::vector<std::string>& scenes,
                                            const std::vector<std::string>& blur, const std::string& sim_seed) {
  const auto names = sim::builtin_scene_names();
  require_blur_per_scene(scenes, blur);
  std::vector<ExperimentScene> out;
  for (size_t i = 0; i < scenes.size(); ++i) {
    const std::string& scene = scenes[i];
    const auto it = std::find(names.begin(), names.end(), scene);
    const bool file = it == names.end() && fs::is_regular_file(scene);
    ExperimentScene s{file ? fs::absolute(scene).string() : scene, file ? fs::path(scene).stem().string() : scene, "",
                      blur[i]};
    if (s.label.empty() || s.label == "." || s.label == "..")
      throw std::invalid_argument("experiment: scene file '" + scene + "' has no usable file stem for its folder");
    for (const auto& o : out)
      if (o.label == s.label)
        throw std::invalid_argument("experiment: two scenes would share the folder '" + s.label + "'");
    if (!sim_seed.empty() && (it != names.end() || file))
      s.seed = sim_seed;
    else if (it != names.end())
      s.seed = builtin_scene_seed(size_t(it - names.begin()));
    else
      throw std::invalid_argument("experiment: '" + scene + "' is not a built-in scene (" + join(names, ", ") + ")" +
                                  (file ? "; a scene file needs --sim-seed N" : " nor a scene file"));
    out.push_back(s);
  }
  return out;
}

}  // namespace

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string ExperimentPlan::help() {
  const auto names = sim::builtin_scene_names();
  std::string seeds;  // "default 1, gallery 2, ..."
  for (size_t i = 0; i < names.size(); ++i) seeds += (i ? ", " : "") + names[i] + " " + builtin_scene_seed(i);
  char buf[8192];
  std::snprintf(
      buf, sizeof buf,
      "usage: evflow experiment --out DIR [--scenes %s] [--blur-px B,...]\n"
      "         [--width 173] [--height 130] [--methods "
      "plain,edi,blur-only,blur+events(,blur+events+warp,blur+events+flow)] [--preset "
      "fast]\n"
      "         [--pose-noise-rot 0.4] [--pose-noise-trans 0.01] [--sim-seed N] [--refine-iters 30] [--device "
      "N|name]\n"
      "         [--no-baseline-pose-refine] [--poses perturbed|colmap] [--emit-jobs FILE | --job] [key=value ...]\n"
      "         [--sim-seeds A,B,...] [--ablation] [--shake smooth|jerk]\n"
      "       evflow experiment --collect DIR\n"
      "  Simulates each built-in scene (its own blur size, or --blur-px: one per scene or one for all;\n"
      "  recorded poses perturbed like poses estimated from blurry images), trains every method on it\n"
      "  with the preset\n"
      "  and the key=value overrides, evaluates (deblur at mid-exposure; novel views as given and after\n"
      "  test-pose refinement) and writes DIR/experiment.md and DIR/experiment.json.\n"
      "  Each scene is simulated with its own seed (%s), so a scene's data\n"
      "  do not depend on which scenes are listed; --sim-seed N uses N for every scene instead;\n"
      "  --sim-seeds A,B,... simulates every scene once per seed, into DIR/<scene>-s<seed>/.\n"
      "  --ablation: the paper's ablation (Table 3): the methods are its seven rows (blur-only,\n"
      "  blur+events, blur+events+warp, blur+res, blur+events+warp+res, evflow-no-ldi-events, evflow),\n"
      "  the seeds --sim-seeds 1,2 unless given, and DIR/ablation.md holds the table (rows averaged\n"
      "  over the scenes and seeds, with each one's deblur PSNR).\n"
      "  --shake jerk: the simulator's camera shake with a sudden change of velocity inside each exposure\n"
      "  (evflow simulate --shake), the non-uniform motion the flow-upsampled blur is for (default: smooth).\n"
      "  A scene may be a glTF file (.glb/.gltf; needs --sim-seed): its data and runs go to DIR/<file stem>/.\n"
      "  plain and edi refine each training view's pose while they train (pose_refine=true), as the blur\n"
      "  methods do through their trajectories; --no-baseline-pose-refine turns that off.\n"
      "  --poses colmap: every method trains on the scene's poses estimated by COLMAP on EDI frames\n"
      "  (`evflow poses`, into DIR/<scene>/data_colmap/; runs in DIR/<scene>/colmap/<method>/) instead of\n"
      "  the perturbed recorded poses (default: perturbed).\n"
      "  --emit-jobs FILE: run nothing; write DIR/experiment_plan.json and FILE, one self-contained command\n"
      "  line per (scene, method) for a batch scheduler (docs/cluster.md). --collect DIR: the table of\n"
      "  those runs once they have finished (an error lists the runs that have not). --job: what an\n"
      "  emitted line runs: the listed scenes and methods, without writing the plan or the table.\n",
      join(names, ",").c_str(), seeds.c_str());
  return buf;
}

ExperimentPlan ExperimentPlan::from_args(ArgParser& p) {
  auto value_or = [&](const char* key, const std::string& fallback) {
    std::string v = p.value(key);
    return v.empty() ? fallback : v;
  };
  ExperimentPlan e;
  const std::string out = p.value("--out");
  const auto scenes = split(value_or("--scenes", join(sim::builtin_scene_names(), ",")));
  std::vector<std::string> blur = split(p.value("--blur-px"));
  if (blur.empty())  // each scene's own: a built-in's, else the default scene's
    for (const auto& sc : scenes) {
      const auto names = sim::builtin_scene_names();
      const bool builtin = std::find(names.begin(), names.end(), sc) != names.end();
      char v[32];
      std::snprintf(v, sizeof v, "%g", sim::builtin_scene_blur_px(builtin ? sc : "default"));
      blur.push_back(v);
    }
  else if (blur.size() == 1)  // one size for every scene
    blur.resize(scenes.size(), blur.front());
  e.width = value_or("--width", e.width), e.height = value_or("--height", e.height);
  const std::string methods = p.value("--methods");
  e.methods = split(methods.empty() ? "plain,edi,blur-only,blur+events" : methods);
  e.preset = value_or("--preset", e.preset);
  e.refine_iters = value_or("--refine-iters", e.refine_iters);
  e.noise_rot = value_or("--pose-noise-rot", e.noise_rot);
  e.noise_trans = value_or("--pose-noise-trans", e.noise_trans);
  e.device = p.value("--device");
  e.sim_seed = p.value("--sim-seed");
  e.sim_seeds = split(p.value("--sim-seeds"));
  e.ablation = p.flag("--ablation");
  e.baseline_pose_refine = !p.flag("--no-baseline-pose-refine");
  e.poses = value_or("--poses", e.poses);
  e.shake = value_or("--shake", e.shake);
  p.reject_unknown();
  require_number("--width", e.width, 1, double(kMaxImageSide), true);
  require_number("--height", e.height, 1, double(kMaxImageSide), true);
  require_number("--refine-iters", e.refine_iters, 0, 1000000, true);
  require_number("--pose-noise-rot", e.noise_rot, 0, 180), require_number("--pose-noise-trans", e.noise_trans, 0, 1e6);
  for (const auto& b : blur) require_number("--blur-px", b, 0, 1e6);
  if (e.shake != "smooth" && e.shake != "jerk")
    throw std::invalid_argument("--shake must be smooth or jerk, got '" + e.shake + "'");
  if (e.poses != "perturbed" && e.poses != "colmap")
    throw std::invalid_argument("--poses must be perturbed or colmap, got '" + e.poses + "'");
  if (!e.sim_seed.empty() && e.sim_seed.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("--sim-seed needs a non-negative integer, got '" + e.sim_seed + "'");
  for (const auto& seed : e.sim_seeds)
    if (seed.find_first_not_of("0123456789") != std::string::npos)
      throw std::invalid_argument("--sim-seeds needs non-negative integers, got '" + seed + "'");
  if (!e.sim_seed.empty() && !e.sim_seeds.empty())
    throw std::invalid_argument("experiment: --sim-seed and --sim-seeds exclude each other");
  if (e.ablation) {
    if (!methods.empty()) throw std::invalid_argument("experiment: --ablation sets the methods; drop --methods");
    e.methods = ablation_methods();
    if (e.sim_seed.empty() && e.sim_seeds.empty()) e.sim_seeds = {"1", "2"};
  }
  for (auto& s : p.positional()) {
    if (s.find('=') == std::string::npos) throw std::invalid_argument("experiment: unexpected argument '" + s + "'");
    e.overrides.push_back(s);
  }
  if (out.empty()) throw std::invalid_argument("usage: evflow experiment --out DIR (see --help)");
  e.out = fs::absolute(out);
  for (auto& m : e.methods) {
    auto all = TrainConfig::methods();
    if (std::find(all.begin(), all.end(), m) == all.end())
      throw std::invalid_argument("experiment: unknown method '" + m + "'");
  }
  TrainConfig probe = TrainConfig::preset_named(e.preset);  // the overrides, before hours of work
  for (auto& kv : e.overrides) probe.set(kv.substr(0, kv.find('=')), kv.substr(kv.find('=') + 1));
  e.scenes = e.sim_seeds.empty() ? resolve_scenes(scenes, blur, e.sim_seed) : resolve_scenes(scenes, blur, e.sim_seeds);
  return e;
}

nlohmann::json ExperimentPlan::to_json() const {
  nlohmann::json sc = nlohmann::json::array();
  for (const auto& s : scenes)
    sc.push_back({{"scene", s.scene}, {"label", s.label}, {"seed", s.seed}, {"blur_px", s.blur_px}});
  return {{"out", out.string()},
          {"scenes", sc},
          {"methods", methods},
          {"width", width},
          {"height", height},
          {"preset", preset},
          {"refine_iters", refine_iters},
          {"pose_noise_rot", noise_rot},
          {"pose_noise_trans", noise_trans},
          {"sim_seed", sim_seed},
          {"sim_seeds", sim_seeds},
          {"ablation", ablation},
          {"device", device},
          {"baseline_pose_refine", baseline_pose_refine},
          {"poses", poses},
          {"shake", shake},
          {"overrides", overrides}};
}

ExperimentPlan ExperimentPlan::read(const fs::path& dir) {
  const fs::path path = dir / "experiment_plan.json";
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error(path.string() + ": missing (write it with evflow experiment --out " + dir.string() +
                             " --emit-jobs FILE)");
  ExperimentPlan e;
  try {
    const nlohmann::json j = nlohmann::json::parse(f);
    for (const auto& s : j.at("scenes"))
      e.scenes.push_back({s.at("scene").get<std::string>(), s.at("label").get<std::string>(),
                          s.at("seed").get<std::string>(), s.at("blur_px").get<std::string>()});
    j.at("methods").get_to(e.methods);
    j.at("width").get_to(e.width), j.at("height").get_to(e.height), j.at("preset").get_to(e.preset);
    j.at("refine_iters").get_to(e.refine_iters);
    j.at("pose_noise_rot").get_to(e.noise_rot), j.at("pose_noise_trans").get_to(e.noise_trans);
    j.at("sim_seed").get_to(e.sim_seed), j.at("device").get_to(e.device);
    j.at("baseline_pose_refine").get_to(e.baseline_pose_refine);
    j.at("overrides").get_to(e.overrides);
    e.poses = j.value("poses", std::string("perturbed"));
    e.sim_seeds = j.value("sim_seeds", std::vector<std::string>{});
    e.ablation = j.value("ablation", false);
    e.shake = j.value("shake", std::string("smooth"));
  } catch (const std::exception& ex) { throw std::runtime_error(path.string() + ": " + ex.what()); }
  e.out = fs::absolute(dir);  // the folder it was read from (it may have moved since)
  return e;
}

void ExperimentPlan::write() const {
  fs::create_directories(out);
  io::write_file_atomic(out / "experiment_plan.json",
                        [&](const fs::path& tmp) { std::ofstream(tmp) << to_json().dump(2) << "\n"; });
}

static std::string device_option(const std::string& device) {
  return device.empty() ? "" : " --device " + shell_quote(device);
}

std::string ExperimentPlan::simulate_command(const std::string& self, size_t si, const fs::path& data) const {
  const ExperimentScene& s = scenes.at(si);
  return shell_quote(self) + " simulate --scene " + shell_quote(s.scene) + " --out " + shell_quote(data.string()) +
         " --width " + shell_quote(width) + " --height " + shell_quote(height) + " --blur-px " +
         shell_quote(s.blur_px) + " --pose-noise-rot " + shell_quote(noise_rot) + " --pose-noise-trans " +
         shell_quote(noise_trans) + " --seed " + s.seed + (shake == "smooth" ? "" : " --shake " + shell_quote(shake)) +
         device_option(device);
}

std::string ExperimentPlan::poses_command(const std::string& self, size_t si, const fs::path& dest) const {
  return shell_quote(self) + " poses " + shell_quote(data_dir(si).string()) + " --out " + shell_quote(dest.string());
}

std::string ExperimentPlan::train_command(const std::string& self, size_t si, const std::string& m) const {
  std::string cmd = shell_quote(self) + " train " + shell_quote(train_data_dir(si).string()) + " --out " +
                    shell_quote(run_dir(si, m).string()) + " --preset " + shell_quote(preset) +
                    " method=" + shell_quote(m);
  if (baseline_pose_refine && (m == "plain" || m == "edi")) cmd += " pose_refine=true";  // before the overrides
  for (auto& kv : overrides) cmd.append(" ").append(shell_quote(kv));
  return cmd + device_option(device);
}

std::string ExperimentPlan::eval_command(const std::string& self, size_t si, const std::string& m) const {
  return shell_quote(self) + " eval " + shell_quote(run_dir(si, m).string()) + " --refine-iters " +
         shell_quote(refine_iters) + device_option(device);
}

std::string ExperimentPlan::job_line(const std::string& self, size_t si, const std::string& m) const {
  const ExperimentScene& s = scenes.at(si);
  std::string line = shell_quote(self) + " experiment --job --out " + shell_quote(out.string()) + " --scenes " +
                     shell_quote(s.scene) + " --blur-px " + shell_quote(s.blur_px) + " --methods " + shell_quote(m) +
                     " --width " + shell_quote(width) + " --height " + shell_quote(height) + " --preset " +
                     shell_quote(preset) + " --refine-iters " + shell_quote(refine_iters) + " --pose-noise-rot " +
                     shell_quote(noise_rot) + " --pose-noise-trans " + shell_quote(noise_trans);
  if (!sim_seed.empty()) line += " --sim-seed " + sim_seed;
  if (!sim_seeds.empty()) line += " --sim-seeds " + s.seed;  // the one seed of this scene's folder
  if (!baseline_pose_refine) line += " --no-baseline-pose-refine";
  if (poses != "perturbed") line += " --poses " + shell_quote(poses);
  if (shake != "smooth") line += " --shake " + shell_quote(shake);
  line += device_option(device);
  for (auto& kv : overrides) line.append(" ").append(shell_quote(kv));
  return line;
}

}  // namespace evflow::app
