#include "flow/flow_colour.h"

#include <algorithm>
#include <cmath>

namespace evflow::flow {

std::vector<uint8_t> flow_colour_wheel(const std::vector<float>& flow, double max_px) {
  std::vector<uint8_t> rgb(flow.size() / 2 * 3, 0);
  for (size_t i = 0; i < flow.size() / 2; ++i) {
    const double u = flow[i * 2], v = flow[i * 2 + 1];
    if (!std::isfinite(u) || !std::isfinite(v)) continue;
    const double h = (std::atan2(v, u) / M_PI + 1.0) * 3.0;  // [0, 6]
    const double s = std::min(1.0, std::hypot(u, v) / std::max(max_px, 1e-9));
    const int k = int(h) % 6;
    const double f = h - std::floor(h);
    const double p = 1 - s, q = 1 - s * f, t = 1 - s * (1 - f);
    const double c[6][3] = {{1, t, p}, {q, 1, p}, {p, 1, t}, {p, q, 1}, {t, p, 1}, {1, p, q}};
    for (int ch = 0; ch < 3; ++ch) rgb[i * 3 + ch] = uint8_t(std::lround(255 * c[k][ch]));
  }
  return rgb;
}

}  // namespace evflow::flow
