// The events panel's picture of one training view's exposure: per pixel, the sum of the
// polarities of the events inside [exposure_start, exposure_end), shown red (net brighter) or
// blue (net darker) on mid grey. Header-only: the viewer test checks the panel against it.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/image.h"
#include "viewer/signed_image.h"

namespace evflow::viewer {

struct EventImage {
  uint32_t width = 0, height = 0;
  std::vector<int32_t> sum;           // net polarity per pixel, row-major
  std::vector<float> rgb;             // planar sRGB [3][H][W] (what the canvas shows)
  size_t positive = 0, negative = 0;  // events counted (EBAD-NeRF counts: sums of the bins)
  bool has_events = false;            // the dataset carries events for this view
};

// Colour scale (signed_image.h): a pixel whose |sum| reaches k = max(1, the 95th percentile of
// the nonzero |sum|) is pure red (255, 0, 0) or pure blue (0, 0, 255); sum 0 is grey (byte 128).
inline EventImage event_image(const io::Dataset& data, size_t v) {
  if (v >= data.train.size())
    throw std::out_of_range("event_image: training view " + std::to_string(v) + " of " +
                            std::to_string(data.train.size()));
  const io::View& view = data.train[v];
  EventImage e;
  const bool ebad = !data.event_counts.empty() && data.event_counts_shape.size() == 3;
  if (data.events.width > 0 && data.events.height > 0) {
    e.width = data.events.width;
    e.height = data.events.height;
  } else {
    e.width = view.camera.width;
    e.height = view.camera.height;
  }
  const size_t hw = size_t(e.width) * e.height;
  e.sum.assign(hw, 0);
  if (ebad && data.event_counts_shape[2] == hw && v < data.event_counts_shape[0]) {
    e.has_events = true;
    const size_t bins = data.event_counts_shape[1];
    for (size_t b = 0; b < bins; ++b) {
      const float* row = data.event_counts.data() + (v * bins + b) * hw;
      for (size_t i = 0; i < hw; ++i) {
        const int32_t c = int32_t(std::lround(row[i]));
        e.sum[i] += c;
        (c > 0 ? e.positive : e.negative) += size_t(std::abs(c));
      }
    }
  } else if (data.events.size() > 0) {
    e.has_events = true;
    const auto [a, b] = data.events.window(view.exposure_start, view.exposure_end);
    for (size_t k = a; k < b; ++k) {
      const size_t i = size_t(data.events.y[k]) * e.width + data.events.x[k];
      if (i >= hw) continue;
      e.sum[i] += data.events.p[k];
      (data.events.p[k] > 0 ? e.positive : e.negative) += 1;
    }
  }
  const std::vector<float> sums(e.sum.begin(), e.sum.end());
  e.rgb = signed_colours(sums, std::max(1.0, signed_scale(sums)));
  return e;
}

}  // namespace evflow::viewer
