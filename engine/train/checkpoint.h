// Training checkpoints: the step, the Gaussians and the optimizer state (Adam moments and step
// counts per parameter group), so that a resumed run continues bit-identically on the same
// device. Written atomically (temporary file, then rename).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "splat/gaussians.h"

namespace evflow {

struct OptimizerGroupState {
  std::string name;
  uint64_t step = 0;
  std::vector<float> exp_avg, exp_avg_sq;
};

// A training view's exposure trajectory (engine/camera: 9 se(3) knots) and its Adam state.
struct TrajectoryState {
  uint64_t step = 0;
  std::vector<double> knots, exp_avg, exp_avg_sq;  // 54 each
};

struct Checkpoint {
  uint32_t step = 0;
  GaussianCloud cloud;
  std::vector<OptimizerGroupState> optimizer;  // empty: fresh optimizer state
  std::vector<TrajectoryState> trajectories;   // one per training view (blur mode); empty otherwise
};

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& ckpt);
// Throws std::runtime_error naming the file on a missing, truncated or malformed checkpoint.
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace evflow
