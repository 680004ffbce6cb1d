// Events on the GPU for training: the events of each training view's exposure window, packed one
// uint per event (shaders/events/events_layout.h) in one buffer, views one after another. The
// host keeps each view's sorted times, so a time window becomes an index range (binary search)
// and the kernels never see a timestamp.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "events/event_stream.h"
#include "events/interval_events.h"
#include "gpu/buffer.h"
#include "gpu/commands.h"

namespace evflow {

struct EventWindow {
  double t0 = 0, t1 = 0;  // events with t0 <= t < t1
};

class GpuEvents : public IntervalEvents {
 public:
  // Packs and uploads the events of `stream` inside each window. `source` names the data in
  // errors (a sensor wider or taller than 32767 pixels, an empty or reversed window, more events
  // than one binding holds).
  GpuEvents(gpu::Context& ctx, const EventStream& stream, const std::vector<EventWindow>& windows,
            const std::string& source);

  uint32_t width() const override { return width_; }
  uint32_t height() const override { return height_; }
  size_t window_count() const override { return windows_.size(); }
  bool float_planes() const override { return false; }
  const EventWindow& window(size_t w) const { return windows_[w]; }
  size_t size() const { return times_.size(); }
  // Events of window w with t0 <= t < t1 (clamped to the window): [first, last) in the packed buffer.
  std::pair<uint32_t, uint32_t> range(size_t w, double t0, double t1) const;
  // Records the per-pixel positive / negative counts of window w's events in [t0, t1) into plane
  // `plane` of `counts` (uint, 2 * H * W per plane, added to what is there: clear it first).
  void accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                  uint32_t plane) const override;
  const gpu::Buffer& packed() const { return packed_; }

 private:
  uint32_t width_ = 0, height_ = 0;
  std::vector<EventWindow> windows_;
  std::vector<size_t> first_;  // per window: offset of its events (size windows + 1)
  std::vector<double> times_;  // per packed event
  gpu::Buffer packed_;
};

}  // namespace evflow
