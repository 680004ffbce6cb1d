// Ground-truth flow of a simulated exposure's intervals (evflow flow, flow=gt in training): from the simulator's
// gt/trajectories.json (the sub-frame poses) and gt/depth/<view>.npy (depth at mid-exposure).
#pragma once
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "camera/camera.h"

namespace evflow::sim {

// For each interval [u_j, u_{j+1}] (normalised exposure times) of training view `name`: the
// displacement over the interval of the surface point seen at each pixel at mid-exposure,
// H * W * 2 (NaN where no surface or out of view). nullopt when `data` has no ground truth.
// Sub-frame poses are interpolated by projecting at the two nearest sub-frames and blending the
// pixel positions linearly in time (the sub-frames are at most half a pixel apart).
std::optional<std::vector<std::vector<float>>> ground_truth_interval_flow(const std::filesystem::path& data,
                                                                          const std::string& name,
                                                                          const std::vector<double>& frame_u);

// The simulator's true mid-exposure camera of training view `name` (gt/trajectories.json's
// gt_camera); nullopt when `data` has no ground truth.
std::optional<Camera> ground_truth_mid_camera(const std::filesystem::path& data, const std::string& name);

// A dense flow's endpoint error against the truth (each H * W * 2), over the pixels with events
// (`counts`, H * W) where the truth is defined.
struct EndpointError {
  double sum = 0;        // of |estimate - truth|
  double truth_sum = 0;  // of |truth|
  size_t n = 0;          // pixels counted
  double mean() const { return n ? sum / double(n) : NAN; }
  double truth_mean() const { return n ? truth_sum / double(n) : NAN; }
};
EndpointError endpoint_error(const std::vector<float>& estimate, const std::vector<float>& truth,
                             const std::vector<uint32_t>& counts);

}  // namespace evflow::sim
