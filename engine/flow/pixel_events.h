// The events of one exposure stored pixel by pixel, the flow estimator's input layout: for each
// pixel its events in time order (CSR), times normalised to the exposure, polarity dropped
// (contrast maximisation counts events of both signs alike).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "events/event_stream.h"

namespace evflow::flow {

struct PixelEvents {
  uint32_t width = 0, height = 0;
  double t0 = 0, t1 = 0;        // the exposure
  std::vector<uint32_t> first;  // H * W + 1 offsets into time
  std::vector<float> time;      // (t - t0) / (t1 - t0), in [0, 1)
  std::vector<uint32_t> order;  // the pixels with events, most events first (ties: by index)
  size_t size() const { return time.size(); }
};

// The events of `stream` with t0 <= t < t1. Throws naming `source` on an empty or non-finite
// window or more events than a 32-bit index holds.
PixelEvents pixel_events(const EventStream& stream, double t0, double t1, const std::string& source);

// Per-pixel count of the events with a <= normalised time < b (H * W).
std::vector<uint32_t> event_counts(const PixelEvents& ev, double a, double b);

}  // namespace evflow::flow
