// Training checkpoints: the step, the Gaussians and the optimizer state (Adam moments and step
// counts per parameter group), so that a resumed run continues bit-identically on the same
// device. Written atomically (temporary file, then rename). Format version 6: version 5's layout
// with each camera state followed by its mid-exposure pose's Adam moments (0 or 6 each); version
// 5 is version 4's layout followed by a CRC-32 of all the bytes before it. Versions 4 (no
// checksum) and 5 are still read.
#pragma once
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "nn/safetensors.h"
#include "splat/gaussians.h"

namespace evflow {

struct OptimizerGroupState {
  std::string name;
  uint64_t step = 0;
  std::vector<float> exp_avg, exp_avg_sq;
};

// A training view's learned camera and its Adam state: the exposure trajectory in blur mode
// (engine/camera: 9 se(3) knots, 54 values) or the pose refinement delta in plain mode (6 values).
struct TrajectoryState {
  uint64_t step = 0;
  std::vector<double> knots, exp_avg, exp_avg_sq;  // 54 or 6 each
  // The mid-exposure pose's own Adam (edi_mid_lr): 6 moments each, or empty.
  uint64_t mid_step = 0;
  std::vector<double> mid_exp_avg, mid_exp_avg_sq;
};

struct Checkpoint {
  uint32_t step = 0;
  GaussianCloud cloud;
  std::vector<OptimizerGroupState> optimizer;  // empty: fresh optimizer state
  std::vector<TrajectoryState>
      trajectories;  // one per training view (blur mode, or plain mode with pose_refine); else empty
  // The LDI branch's weights and Adam state (ldi=on). Not part of the .ckpt file: `evflow train`
  // keeps it as RUN/ldi.safetensors beside it.
  std::optional<nn::SafetensorsFile> ldi;
  std::string ldi_source;  // the file it came from, for errors
};

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& ckpt);
// Throws std::runtime_error naming the file on a missing, truncated or malformed checkpoint, and
// on a checksum mismatch (a damaged file: flipped bits, cut short or grown).
Checkpoint read_checkpoint(const std::filesystem::path& path);
// The same from the file's bytes in memory; `name` names the file in errors.
Checkpoint parse_checkpoint(const std::string& name, const uint8_t* data, size_t size);

}  // namespace evflow
