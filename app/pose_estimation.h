// Camera poses of a dataset by COLMAP (`evflow poses`): each training view as one frame (its EDI
// estimate at mid-exposure, or the blurry image), each novel view's sharp image, all registered in
// one COLMAP model whose frame the new dataset keeps. Near/far and the sparse points come from the
// model; when the input has poses of its own, they are the reference the estimate is scored against.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "camera/similarity.h"
#include "colmap_run.h"
#include "io/dataset.h"

namespace evflow::app {

struct PoseOptions {
  bool edi = true;  // false: the blurry frames go to COLMAP
  ColmapSettings colmap;
};

struct PoseEstimate {
  io::Dataset dataset;                        // the input with COLMAP's poses, near/far and points
  std::vector<std::string> missing;           // views COLMAP did not register (dataset poses then invalid)
  std::vector<std::string> registered_views;  // the others, training views first
  size_t views = 0;                           // training + novel views sent to COLMAP
  std::optional<PoseErrors> errors;           // registered views vs the input's poses, when it had any
  double reprojection_px = 0;                 // mean over the sparse points
};

// Writes the frames to work/images/, runs COLMAP in `work` and converts its model. Throws when
// the input cannot give frames (EDI without events) or COLMAP fails.
PoseEstimate estimate_poses(const io::Dataset& input, const std::filesystem::path& work, const PoseOptions& opt);

// The report of an estimate as JSON (work/report.json).
nlohmann::json pose_report(const PoseEstimate& e, const PoseOptions& opt);

}  // namespace evflow::app
