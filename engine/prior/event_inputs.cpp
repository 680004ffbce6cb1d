#include "prior/event_inputs.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace evflow::prior {

std::vector<float> event_planes(const EventStream& events, double t0, double t1, const std::vector<double>& u) {
  if (u.size() < 3 || u.size() % 2 == 0)
    throw std::invalid_argument("residual prior: needs an odd number (>= 3) of virtual frames, got " +
                                std::to_string(u.size()));
  const size_t n = u.size() / 2, hw = size_t(events.width) * events.height;
  std::vector<double> times(u.size());
  for (size_t i = 0; i < u.size(); ++i) times[i] = t0 + u[i] * (t1 - t0);
  std::vector<float> planes(2 * (u.size() - 1) * hw, 0.0f);
  const auto [first, last] = events.window(times.front(), std::nextafter(times.back(), INFINITY));
  for (size_t k = first; k < last; ++k) {
    const double t = events.t[k];
    const size_t pixel = size_t(events.y[k]) * events.width + events.x[k];
    const size_t pol = events.p[k] > 0 ? 0 : 1;
    const float value = events.p[k] > 0 ? kEventScale : -kEventScale;
    for (size_t i = 0; i < u.size(); ++i) {
      if (i == n) continue;
      const bool after = i > n;
      const bool inside = after ? (t > times[n] && t <= times[i]) : (t > times[i] && t <= times[n]);
      if (!inside) continue;
      const size_t plane = 2 * (after ? i - 1 : i) + pol;
      planes[plane * hw + pixel] += after ? value : -value;
    }
  }
  return planes;
}

std::vector<float> network_input(const std::vector<float>& blurry_hwc, const std::vector<float>& event_planes,
                                 uint32_t width, uint32_t height) {
  const size_t hw = size_t(width) * height;
  if (blurry_hwc.size() != 3 * hw || event_planes.size() % hw != 0)
    throw std::invalid_argument("residual prior: the blurry image or the event planes do not match " +
                                std::to_string(width) + "x" + std::to_string(height));
  std::vector<float> in(3 * hw + event_planes.size());
  for (size_t p = 0; p < hw; ++p)
    for (size_t c = 0; c < 3; ++c) in[c * hw + p] = blurry_hwc[p * 3 + c];
  std::copy(event_planes.begin(), event_planes.end(), in.begin() + 3 * hw);
  return in;
}

}  // namespace evflow::prior
