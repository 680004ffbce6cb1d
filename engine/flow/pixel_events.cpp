#include "flow/pixel_events.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace evflow::flow {

PixelEvents pixel_events(const EventStream& stream, double t0, double t1, const std::string& source) {
  if (!(std::isfinite(t0) && std::isfinite(t1)) || t1 <= t0)
    throw std::runtime_error(source + ": exposure [" + std::to_string(t0) + ", " + std::to_string(t1) +
                             ") is empty or not finite");
  PixelEvents ev;
  ev.width = stream.width;
  ev.height = stream.height;
  ev.t0 = t0;
  ev.t1 = t1;
  const size_t hw = size_t(stream.width) * stream.height;
  const auto [a, b] = stream.window(t0, t1);
  if (b - a > 0xFFFFFFFFull) throw std::runtime_error(source + ": more than 2^32 events in one exposure");
  ev.first.assign(hw + 1, 0);
  for (size_t i = a; i < b; ++i) ++ev.first[size_t(stream.y[i]) * stream.width + stream.x[i] + 1];
  for (size_t p = 0; p < hw; ++p) ev.first[p + 1] += ev.first[p];
  ev.time.resize(b - a);
  std::vector<uint32_t> next(ev.first.begin(), ev.first.end() - 1);
  const double scale = 1.0 / (t1 - t0);
  for (size_t i = a; i < b; ++i) {  // time order in, so each pixel's list stays in time order
    const size_t p = size_t(stream.y[i]) * stream.width + stream.x[i];
    ev.time[next[p]++] = std::min(float((stream.t[i] - t0) * scale), std::nextafter(1.0f, 0.0f));
  }
  for (uint32_t p = 0; p < hw; ++p)
    if (ev.first[p + 1] > ev.first[p]) ev.order.push_back(p);
  std::stable_sort(ev.order.begin(), ev.order.end(), [&](uint32_t a, uint32_t b) {
    return ev.first[a + 1] - ev.first[a] > ev.first[b + 1] - ev.first[b];
  });
  return ev;
}

std::vector<uint32_t> event_counts(const PixelEvents& ev, double a, double b) {
  std::vector<uint32_t> n(size_t(ev.width) * ev.height, 0);
  for (size_t p = 0; p < n.size(); ++p)
    for (uint32_t e = ev.first[p]; e < ev.first[p + 1]; ++e) n[p] += ev.time[e] >= a && ev.time[e] < b;
  return n;
}

}  // namespace evflow::flow
