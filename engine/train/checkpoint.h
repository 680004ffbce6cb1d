// Training checkpoints: the Gaussians and the step, written atomically (temporary + rename).
#pragma once
#include <filesystem>

#include "splat/gaussians.h"

namespace evflow {

struct Checkpoint {
  uint32_t step = 0;
  GaussianCloud cloud;
};

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& ckpt);
// Throws std::runtime_error naming the file on a missing, truncated or malformed checkpoint.
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace evflow
