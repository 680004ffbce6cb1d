#include "ldi/crop_events.h"

#include <stdexcept>
#include <string>

namespace evflow::ldi {

CropEvents::CropEvents(const GpuEvents& events, uint32_t crop_w, uint32_t crop_h)
    : events_(events), crop_{0, 0, crop_w, crop_h} {
  check_crop(crop_, events.width(), events.height(), "LDI event crop");
}

void CropEvents::set_crop(const Crop& crop) {
  if (crop.w != crop_.w || crop.h != crop_.h)
    throw std::invalid_argument("LDI event crop: " + std::to_string(crop.w) + "x" + std::to_string(crop.h) +
                                " instead of " + std::to_string(crop_.w) + "x" + std::to_string(crop_.h));
  check_crop(crop, events_.width(), events_.height(), "LDI event crop");
  if (crop.x != crop_.x || crop.y != crop_.y) ++generation_;
  crop_ = crop;
}

void CropEvents::accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                            uint32_t plane) const {
  record_crop_counts(cmd, events_, w, t0, t1, crop_, counts, plane);
}

}  // namespace evflow::ldi
