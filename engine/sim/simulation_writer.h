// The simulator's output folder: the dataset in our layout plus the ground truth.
#pragma once
#include <filesystem>

#include "sim/simulator.h"

namespace evflow::sim {

// Writes `result` into `dir` in our layout (io::write_evflow_dataset, blurry as 8-bit sRGB PNG,
// simulator settings and statistics under dataset.json's "simulator" key) plus the ground truth:
//   gt/trajectories.json   per training view: exposure, gt and recorded mid pose, sub-frame times and poses
//   gt/depth/<view>.npy    float32 [H, W] depth of the mid-exposure (train) / novel frame, 0 = background
//   gt/flow/<view>_mid.npy float32 [H, W, 2] flow of the interval starting at mid-exposure
// (per-interval flows: `flow_all` in the CLI writes gt/flow/<view>_<k>.npy while simulating).
void write_simulation(const SimResult& result, const std::filesystem::path& dir);

}  // namespace evflow::sim
