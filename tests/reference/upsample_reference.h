// Double-precision CPU reference of the flow-upsampled blur's mean (engine/train/image_model.h,
// shaders/train/train_layout.h). The taps' discrete choices (rounding, floor) are made in float,
// as the shaders make them; the sums are in double.
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::reference {

// The mean of the 2NM + 1 frames: `frames` (planar linear RGB, 3 * H * W each) and, for each
// interval i, M - 1 sub-frames of frame i moved along flow planes [2 i H W, 2 (i + 1) H W) (dx, dy).
std::vector<double> upsampled_mean(const std::vector<std::vector<double>>& frames, const std::vector<float>& flow,
                                   uint32_t width, uint32_t height, uint32_t upsample, int reach = 2);

}  // namespace evflow::reference
