#include "events/warped_events.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace evflow {

std::vector<float> warp_events_to_end(const EventStream& s, double ta, double tb, const std::vector<float>& d,
                                      double theta_pos, double theta_neg) {
  const size_t W = s.width, H = s.height, hw = W * H;
  if (d.size() != hw * 2)
    throw std::invalid_argument("warp_events_to_end: displacement field has " + std::to_string(d.size()) +
                                " values, the " + std::to_string(W) + "x" + std::to_string(H) + " sensor needs " +
                                std::to_string(hw * 2));
  if (!(tb > ta)) throw std::invalid_argument("warp_events_to_end: empty or reversed interval");
  std::vector<double> acc(hw, 0.0);
  auto vote = [&](long x, long y, double w) {
    if (x >= 0 && y >= 0 && x < long(W) && y < long(H)) acc[size_t(y) * W + size_t(x)] += w;
  };
  const auto [first, last] = s.window(ta, tb);
  for (size_t k = first; k < last; ++k) {
    const size_t p = size_t(s.y[k]) * W + s.x[k];
    const double u = d[2 * p], v = d[2 * p + 1];
    if (!std::isfinite(u) || !std::isfinite(v)) continue;
    const double lever = (tb - s.t[k]) / (tb - ta);
    const double x = s.x[k] + lever * u, y = s.y[k] + lever * v;
    if (std::fabs(x) > 1e7 || std::fabs(y) > 1e7) continue;  // far off the sensor
    const double fx = std::floor(x), fy = std::floor(y), ax = x - fx, ay = y - fy;
    const double amount = s.p[k] > 0 ? theta_pos : -theta_neg;
    const long ix = long(fx), iy = long(fy);
    vote(ix, iy, amount * (1 - ax) * (1 - ay));
    vote(ix + 1, iy, amount * ax * (1 - ay));
    vote(ix, iy + 1, amount * (1 - ax) * ay);
    vote(ix + 1, iy + 1, amount * ax * ay);
  }
  return std::vector<float>(acc.begin(), acc.end());
}

}  // namespace evflow
