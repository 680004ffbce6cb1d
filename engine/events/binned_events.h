// Pre-binned events on the GPU (EBAD-NeRF's layout): per training view, `bins` planes of signed
// per-pixel counts splitting the view's exposure window into equal bins. An interval [t0, t1)
// takes every bin it covers, weighted by the covered fraction of the bin: exact counts when its
// ends fall on bin edges, proportional shares of a bin otherwise. A bin's signed count c is the
// net of its events: max(c, 0) positive and max(-c, 0) negative events.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "events/gpu_events.h"
#include "events/interval_events.h"

namespace evflow {

struct BinWeight {
  uint32_t bin = 0;
  double weight = 0;  // the covered fraction of the bin, in (0, 1]
};
// The bins of a window [w0, w1) cut into `bins` equal parts that [t0, t1) covers (clamped to the
// window), with their weights. An end within 1e-9 of a bin's width of a bin edge counts as on
// the edge, so intervals whose ends are bin edges get weights of exactly 1.
std::vector<BinWeight> bin_weights(double t0, double t1, const EventWindow& window, uint32_t bins);

class BinnedEvents : public IntervalEvents {
 public:
  // `counts` holds shape [windows.size(), bins, width * height] (row v: view v, pixel y * W + x).
  // `source` names the data in errors (a shape that does not match, non-finite counts, an empty
  // or reversed window, more counts than one binding holds).
  BinnedEvents(gpu::Context& ctx, const std::vector<float>& counts, uint32_t bins, uint32_t width, uint32_t height,
               const std::vector<EventWindow>& windows, const std::string& source);

  uint32_t width() const override { return width_; }
  uint32_t height() const override { return height_; }
  size_t window_count() const override { return windows_.size(); }
  bool float_planes() const override { return true; }
  uint32_t bins() const { return bins_; }
  void accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                  uint32_t plane) const override;

 private:
  uint32_t width_ = 0, height_ = 0, bins_ = 0;
  std::vector<EventWindow> windows_;
  gpu::Buffer binned_;
};

}  // namespace evflow
