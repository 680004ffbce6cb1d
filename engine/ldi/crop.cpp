#include "ldi/crop.h"

#include <stdexcept>

#include "ldi/ldi_layout.h"

namespace evflow::ldi {

namespace {

shaderio::LdiCropPC crop_pc(const gpu::Buffer& full, const gpu::Buffer& part, uint32_t width, uint32_t height,
                            uint32_t channels, const Crop& crop) {
  check_crop(crop, width, height, "LDI crop");
  if (full.size() < uint64_t(channels) * width * height * 4 || part.size() < channels * crop.pixels() * 4)
    throw std::invalid_argument("LDI crop: " + full.name() + " or " + part.name() + " is smaller than its image");
  return {channels, width, height, crop.x, crop.y, crop.w, crop.h, 0};
}

}  // namespace

void record_crop(gpu::Commands& cmd, const gpu::Buffer& full, uint32_t width, uint32_t height, uint32_t channels,
                 const Crop& crop, const gpu::Buffer& out) {
  const auto pc = crop_pc(full, out, width, height, channels, crop);
  cmd.dispatch("ldi/crop", {{shaderio::kLdiCropBindFull, full}, {shaderio::kLdiCropBindOut, out}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(channels * crop.pixels(), shaderio::kLdiGroupSize)));
}

void record_uncrop_add(gpu::Commands& cmd, const gpu::Buffer& part, uint32_t width, uint32_t height, uint32_t channels,
                       const Crop& crop, const gpu::Buffer& full) {
  const auto pc = crop_pc(full, part, width, height, channels, crop);
  cmd.dispatch("ldi/uncrop_add", {{shaderio::kLdiCropBindFull, full}, {shaderio::kLdiCropBindOut, part}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(channels * crop.pixels(), shaderio::kLdiGroupSize)));
}

}  // namespace evflow::ldi
