#include "colmap_run.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "experiment_plan.h"  // shell_quote

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

std::string threads_arg(const char* option, const ColmapSettings& s) {
  return s.threads > 0 ? std::string(" --") + option + " " + std::to_string(s.threads) : "";
}

// One step: `colmap <args>` with its output in work/<name>.log; prints the step and its time.
// Throws naming the log when it fails, unless `may_fail`; returns whether it succeeded.
bool step(const fs::path& work, const std::string& name, const std::string& args, const ColmapSettings& s,
          bool may_fail = false) {
  const fs::path log = work / (name + ".log");
  std::printf("  colmap %-18s ", name.c_str());
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string cmd =
      "QT_QPA_PLATFORM=offscreen " + shell_quote(s.binary) + " " + args + " > " + shell_quote(log.string()) + " 2>&1";
  const int rc = std::system(cmd.c_str());
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%.1f s%s\n", secs, rc ? " (failed)" : "");
  if (rc != 0 && !may_fail)
    throw std::runtime_error("COLMAP's " + name + " failed (exit " + std::to_string(rc) + "), see " + log.string());
  return rc == 0;
}

// Registered images of a binary model, from the converted images.txt (two lines per image).
size_t registered_images(const fs::path& text_model) {
  std::ifstream f(text_model / "images.txt");
  size_t lines = 0;
  std::string s;
  while (std::getline(f, s))
    if (s.empty() || s[0] != '#') ++lines;
  return (lines + 1) / 2;
}

}  // namespace

void require_colmap(const ColmapSettings& s) {
  const std::string cmd = shell_quote(s.binary) + " help > /dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("COLMAP ('" + s.binary +
                             "') does not run: install it (Debian: apt-get install colmap; scripts/install-deps.sh "
                             "does) or point EVF_COLMAP at the binary");
}

fs::path run_colmap(const fs::path& work, const Camera& k, const ColmapSettings& s) {
  if (s.matcher != "exhaustive" && s.matcher != "sequential")
    throw std::invalid_argument("--matcher must be exhaustive or sequential, got '" + s.matcher + "'");
  const std::string db = shell_quote((work / "database.db").string());
  const std::string images = shell_quote((work / "images").string());
  fs::remove(work / "database.db");
  fs::remove_all(work / "sparse");
  fs::remove_all(work / "model");
  fs::create_directories(work / "sparse");
  std::ostringstream params;
  params.precision(17);
  params << k.fx << "," << k.fy << "," << k.cx << "," << k.cy;
  step(work, "feature_extractor",
       "feature_extractor --database_path " + db + " --image_path " + images +
           " --ImageReader.camera_model PINHOLE --ImageReader.single_camera 1 --ImageReader.camera_params " +
           params.str() + " --SiftExtraction.use_gpu 0" + threads_arg("SiftExtraction.num_threads", s),
       s);
  step(work, s.matcher + "_matcher",
       s.matcher + "_matcher --database_path " + db + " --SiftMatching.use_gpu 0" +
           threads_arg("SiftMatching.num_threads", s),
       s);
  step(work, "mapper",
       "mapper --database_path " + db + " --image_path " + images + " --output_path " +
           shell_quote((work / "sparse").string()) +
           " --Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_principal_point 0"
           " --Mapper.ba_refine_extra_params 0 --Mapper.min_model_size 3" +
           threads_arg("Mapper.num_threads", s),
       s, true);  // fails when it finds no initial pair: no model, reported as such below
  fs::path best;
  size_t best_count = 0;
  for (const auto& e : fs::directory_iterator(work / "sparse")) {
    if (!e.is_directory()) continue;
    const fs::path text = work / ("model_" + e.path().filename().string());
    fs::create_directories(text);
    step(work, "model_converter_" + e.path().filename().string(),
         "model_converter --input_path " + shell_quote(e.path().string()) + " --output_path " +
             shell_quote(text.string()) + " --output_type TXT",
         s);
    const size_t n = registered_images(text);
    if (n > best_count) best_count = n, best = text;
  }
  if (best.empty()) {
    std::printf("  COLMAP reconstructed nothing (see %s)\n", (work / "mapper.log").c_str());
    return {};
  }
  fs::rename(best, work / "model");
  return work / "model";
}

}  // namespace evflow::app
