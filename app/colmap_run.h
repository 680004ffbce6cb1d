// Runs COLMAP's command-line steps for `evflow poses`: CPU SIFT features with one fixed pinhole
// camera, matching, incremental mapping with the intrinsics held fixed, and the text model of the
// largest reconstruction. Each step's output goes to its own log in the work folder.
#pragma once
#include <filesystem>
#include <string>

#include "camera/camera.h"

namespace evflow::app {

struct ColmapSettings {
  std::string binary = "colmap";       // EVF_COLMAP overrides it
  std::string matcher = "exhaustive";  // or "sequential"
  int threads = 0;                     // 0: COLMAP's default (every core)
};

// Throws std::runtime_error saying how to install COLMAP when `binary` does not run.
void require_colmap(const ColmapSettings& s);

// Runs the steps on work/images/ (every image seen by `intrinsics`), writing work/database.db,
// work/sparse/<k>/, work/<step>.log and the text model of the reconstruction with the most
// registered images to work/model/ (returned; empty when COLMAP reconstructed nothing). Prints
// one line per step. Throws naming the step and its log when a step fails (the mapper excepted:
// it fails when it finds no initial pair).
std::filesystem::path run_colmap(const std::filesystem::path& work, const Camera& intrinsics, const ColmapSettings& s);

}  // namespace evflow::app
