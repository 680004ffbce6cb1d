// Crops of planar images on the GPU (shaders/ldi/crop.comp, uncrop_add.comp): the LDI works on a
// crop of the view (random crops for the fast preset, the whole image otherwise).
#pragma once
#include <cstdint>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "ldi/event_bins.h"

namespace evflow::ldi {

// out[c][y][x] = full[c][crop.y + y][crop.x + x] for c < channels; full is channels x height x width.
void record_crop(gpu::Commands& cmd, const gpu::Buffer& full, uint32_t width, uint32_t height, uint32_t channels,
                 const Crop& crop, const gpu::Buffer& out);
// The adjoint: full[c][crop.y + y][crop.x + x] += part[c][y][x].
void record_uncrop_add(gpu::Commands& cmd, const gpu::Buffer& part, uint32_t width, uint32_t height, uint32_t channels,
                       const Crop& crop, const gpu::Buffer& full);

}  // namespace evflow::ldi
