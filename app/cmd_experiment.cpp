// evflow experiment: the deblurring comparison of the paper's configurations on simulated scenes.
// For every scene: simulate (unless its dataset exists), then train and evaluate every method
// (plain, edi, blur-only, blur+events) with the same preset and overrides, and write one table
// (DIR/experiment.md, DIR/experiment.json). Each run is a separate `evflow train` / `evflow eval`
// process; a run whose eval.json exists is reused, so an interrupted experiment continues.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli.h"
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

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

double run_command(const std::string& cmd, const fs::path& log) {
  const auto t0 = std::chrono::steady_clock::now();
  std::printf("  $ %s\n", cmd.c_str());
  std::fflush(stdout);
  const int rc = std::system((cmd + " >> " + quote(log.string()) + " 2>&1").c_str());
  if (rc != 0)
    throw std::runtime_error("command failed (exit " + std::to_string(rc) + "), see " + log.string() + ": " + cmd);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

static int run_experiment(const Args& a) {
  ArgParser p(a);
  const auto names = sim::builtin_scene_names();
  const std::string all_scenes = join(names, ",");
  if (p.flag("--help")) {
    std::string seeds;  // "default 1, gallery 2, ..."
    for (size_t i = 0; i < names.size(); ++i) seeds += (i ? ", " : "") + names[i] + " " + builtin_scene_seed(i);
    std::printf(
        "usage: evflow experiment --out DIR [--scenes %s] [--blur-px 6,4,9]\n"
        "         [--width 173] [--height 130] [--methods plain,edi,blur-only,blur+events] [--preset fast]\n"
        "         [--pose-noise-rot 0.4] [--pose-noise-trans 0.01] [--sim-seed N] [--refine-iters 30] [--device "
        "N|name]\n"
        "         [--no-baseline-pose-refine] [key=value ...]\n"
        "  Simulates each built-in scene (blur size per scene; recorded poses perturbed like poses estimated\n"
        "  from blurry images), trains every method on it with the preset\n"
        "  and the key=value overrides, evaluates (deblur at mid-exposure; novel views as given and after\n"
        "  test-pose refinement) and writes DIR/experiment.md and DIR/experiment.json.\n"
        "  Each scene is simulated with its own seed (%s), so a scene's data\n"
        "  do not depend on which scenes are listed; --sim-seed N uses N for every scene instead.\n"
        "  A scene may be a glTF file (.glb/.gltf; needs --sim-seed): its data and runs go to DIR/<file stem>/.\n"
        "  plain and edi refine each training view's pose while they train (pose_refine=true), as the blur\n"
        "  methods do through their trajectories; --no-baseline-pose-refine turns that off.\n",
        all_scenes.c_str(), seeds.c_str());
    return 0;
  }
  auto value_or = [&](const char* key, const char* fallback) {
    std::string v = p.value(key);
    return v.empty() ? std::string(fallback) : v;
  };
  const std::string out = p.value("--out");
  const auto scenes = split(value_or("--scenes", all_scenes.c_str()));
  const auto blur = split(value_or("--blur-px", "6,4,9"));
  const std::string width = value_or("--width", "173"), height = value_or("--height", "130");
  const auto methods = split(value_or("--methods", "plain,edi,blur-only,blur+events"));
  const std::string preset = value_or("--preset", "fast");
  const std::string refine = value_or("--refine-iters", "30");
  const std::string noise_rot = value_or("--pose-noise-rot", "0.4"),
                    noise_trans = value_or("--pose-noise-trans", "0.01");
  const std::string device = p.value("--device");
  const std::string sim_seed = p.value("--sim-seed");
  const bool baseline_pose_refine = !p.flag("--no-baseline-pose-refine");
  p.reject_unknown();
  if (!sim_seed.empty() && sim_seed.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("--sim-seed needs a non-negative integer, got '" + sim_seed + "'");
  std::vector<std::string> overrides;
  for (auto& s : p.positional()) {
    if (s.find('=') == std::string::npos) throw std::invalid_argument("experiment: unexpected argument '" + s + "'");
    overrides.push_back(s);
  }
  if (out.empty()) throw std::invalid_argument("usage: evflow experiment --out DIR (see --help)");
  if (blur.size() != scenes.size())
    throw std::invalid_argument("--blur-px needs one value per scene (" + std::to_string(scenes.size()) + ")");
  for (auto& m : methods) {
    auto all = TrainConfig::methods();
    if (std::find(all.begin(), all.end(), m) == all.end())
      throw std::invalid_argument("experiment: unknown method '" + m + "'");
  }
  {  // validate the overrides before hours of work
    TrainConfig probe = TrainConfig::preset_named(preset);
    for (auto& kv : overrides) probe.set(kv.substr(0, kv.find('=')), kv.substr(kv.find('=') + 1));
  }
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string dev = device.empty() ? "" : " --device " + quote(device);
  fs::create_directories(out);
  const fs::path log = fs::path(out) / "experiment.log";
  nlohmann::json table = nlohmann::json::array();
  std::ostringstream md;
  md << "| scene | blur px | method | deblur PSNR | deblur SSIM | novel PSNR | novel SSIM | novel PSNR (refined) | "
        "train s |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  // A scene's simulation seed follows the scene, not its place in --scenes; unknown scenes are
  // refused here, before any work.
  // A scene's folder: its name, or a scene file's stem.
  std::vector<std::string> seeds, labels;
  for (auto& scene : scenes) {
    const auto it = std::find(names.begin(), names.end(), scene);
    const bool file = it == names.end() && fs::is_regular_file(scene);
    labels.push_back(file ? fs::path(scene).stem().string() : scene);
    if (labels.back().empty() || labels.back() == "." || labels.back() == "..")
      throw std::invalid_argument("experiment: scene file '" + scene + "' has no usable file stem for its folder");
    if (std::count(labels.begin(), labels.end(), labels.back()) > 1)
      throw std::invalid_argument("experiment: two scenes would share the folder '" + labels.back() + "'");
    if (!sim_seed.empty() && (it != names.end() || file)) {
      seeds.push_back(sim_seed);
    } else if (it != names.end()) {
      seeds.push_back(builtin_scene_seed(size_t(it - names.begin())));
    } else {
      throw std::invalid_argument("experiment: '" + scene + "' is not a built-in scene (" + join(names, ", ") + ")" +
                                  (file ? "; a scene file needs --sim-seed N" : " nor a scene file"));
    }
  }
  for (size_t si = 0; si < scenes.size(); ++si) {
    const fs::path data = fs::path(out) / labels[si] / "data";
    if (!fs::exists(data / "dataset.json")) {
      std::printf("[%s] simulate\n", labels[si].c_str());
      run_command(quote(self) + " simulate --scene " + quote(scenes[si]) + " --out " + quote(data.string()) +
                      " --width " + width + " --height " + height + " --blur-px " + quote(blur[si]) +
                      " --pose-noise-rot " + quote(noise_rot) + " --pose-noise-trans " + quote(noise_trans) +
                      " --seed " + seeds[si] + dev,
                  log);
    }
    for (auto& m : methods) {
      const fs::path run = fs::path(out) / labels[si] / m;
      double secs = -1;
      if (!fs::exists(run / "eval.json")) {
        std::printf("[%s] %s\n", labels[si].c_str(), m.c_str());
        std::string cmd = quote(self) + " train " + quote(data.string()) + " --out " + quote(run.string()) +
                          " --preset " + quote(preset) + " method=" + quote(m);
        if (baseline_pose_refine && (m == "plain" || m == "edi")) cmd += " pose_refine=true";  // before the overrides
        for (auto& kv : overrides) cmd.append(" ").append(quote(kv));
        cmd.append(dev);
        secs = run_command(cmd, log);
        run_command(quote(self) + " eval " + quote(run.string()) + " --refine-iters " + quote(refine) + dev, log);
        io::write_file_atomic(run / "train_seconds.txt",
                              [&](const fs::path& tmp) { std::ofstream(tmp) << secs << "\n"; });
      } else if (fs::exists(run / "train_seconds.txt")) {
        std::ifstream(run / "train_seconds.txt") >> secs;
      }
      nlohmann::json e;
      std::ifstream f(run / "eval.json");
      try {
        f >> e;
      } catch (const std::exception& ex) { throw std::runtime_error((run / "eval.json").string() + ": " + ex.what()); }
      auto get = [&](const char* set, const char* key) {
        return e.contains(set) ? e[set][key].get<double>() : std::nan("");
      };
      nlohmann::json row = {{"scene", labels[si]},
                            {"blur_px", std::stod(blur[si])},
                            {"method", m},
                            {"deblur_psnr", get("deblur", "mean_psnr")},
                            {"deblur_ssim", get("deblur", "mean_ssim")},
                            {"novel_psnr", get("novel", "mean_psnr")},
                            {"novel_ssim", get("novel", "mean_ssim")},
                            {"novel_refined_psnr", get("novel_refined", "mean_psnr")},
                            {"train_seconds", secs}};
      table.push_back(row);
      char line[320];
      std::snprintf(line, sizeof line, "| %s | %s | %s | %.2f | %.4f | %.2f | %.4f | %.2f | %.0f |\n",
                    labels[si].c_str(), blur[si].c_str(), m.c_str(), row["deblur_psnr"].get<double>(),
                    row["deblur_ssim"].get<double>(), row["novel_psnr"].get<double>(), row["novel_ssim"].get<double>(),
                    row["novel_refined_psnr"].get<double>(), secs);
      md << line;
      std::printf("%s", line);
      // Rewritten after every run, so a partial experiment has its table too.
      io::write_file_atomic(fs::path(out) / "experiment.md",
                            [&](const fs::path& tmp) { std::ofstream(tmp) << md.str(); });
      nlohmann::json j = {{"preset", preset},
                          {"overrides", overrides},
                          {"width", width},
                          {"height", height},
                          {"pose_noise_rot_deg", std::stod(noise_rot)},
                          {"pose_noise_trans", std::stod(noise_trans)},
                          {"baseline_pose_refine", baseline_pose_refine},
                          {"runs", table}};
      io::write_file_atomic(fs::path(out) / "experiment.json",
                            [&](const fs::path& tmp) { std::ofstream(tmp) << j.dump(2) << "\n"; });
    }
  }
  std::printf("\n%s", md.str().c_str());
  return 0;
}

static Command reg("experiment",
                   "train and score plain / edi / blur-only / blur+events on simulated scenes (one table)",
                   run_experiment);

}  // namespace evflow::app
