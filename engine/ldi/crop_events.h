// A training view's events over a crop of the sensor, as the event loss reads them
// (events/interval_events.h): the LDI's event loss L_ev^ldi on its crop-sized frames. The crop
// is set per step; each move changes generation(), so that the loss counts the events again.
#pragma once
#include "events/gpu_events.h"
#include "events/interval_events.h"
#include "ldi/event_bins.h"

namespace evflow::ldi {

class CropEvents : public IntervalEvents {
 public:
  // crop_w x crop_h: the size of every crop (inside the sensor).
  CropEvents(const GpuEvents& events, uint32_t crop_w, uint32_t crop_h);
  void set_crop(const Crop& crop);  // of the size given at construction
  const Crop& crop() const { return crop_; }

  uint32_t width() const override { return crop_.w; }
  uint32_t height() const override { return crop_.h; }
  size_t window_count() const override { return events_.window_count(); }
  bool float_planes() const override { return false; }
  void accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                  uint32_t plane) const override;
  uint64_t generation() const override { return generation_; }

 private:
  const GpuEvents& events_;
  Crop crop_;
  uint64_t generation_ = 0;
};

}  // namespace evflow::ldi
