// How a learned exposure trajectory moves the image compared with the simulator's ground truth:
// the displacement from the start to the end of the exposure of each surface point seen at
// mid-exposure, learned (the trajectory's cameras at u = 0, 0.5, 1, the true mid-exposure depth)
// against true (gt/trajectories.json, gt/depth/<view>.npy). Run backwards, a trajectory that
// matches the blur but not the time direction scores its error under `reversed_error_px`. Where
// the learned mid-exposure camera sees the scene against the true one is `mid_error_px`: a
// trajectory with the right motion in the wrong place scores its misplacement there.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include "camera/camera.h"

namespace evflow {

struct ExposureMotion {
  size_t pixels = 0;             // pixels with a surface in both fields
  double truth_px = 0;           // mean length of the true displacement
  double error_px = 0;           // mean endpoint error of the learned displacement
  double reversed_error_px = 0;  // the same with the learned trajectory run backwards
  double mid_error_px = 0;       // mean distance between each point's pixel in the learned and true mid cameras
  bool reversed() const { return reversed_error_px < error_px; }
};

// nullopt when `data` has no ground truth for training view `view`.
std::optional<ExposureMotion> exposure_motion(const std::filesystem::path& data, const std::string& view,
                                              const Camera& start, const Camera& mid, const Camera& end);

}  // namespace evflow
