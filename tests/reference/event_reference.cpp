#include "reference/event_reference.h"

#include <algorithm>
#include <cmath>

namespace evflow::reference {

std::vector<double> pool_plane(const std::vector<double>& v, uint32_t width, uint32_t height, uint32_t pool) {
  const uint32_t cw = (width + pool - 1) / pool, ch = (height + pool - 1) / pool;
  std::vector<double> out(size_t(cw) * ch, 0.0);
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) out[size_t(y / pool) * cw + x / pool] += v[size_t(y) * width + x];
  return out;
}

double event_loss(const EventLossInputs& in) {
  const size_t hw = size_t(in.width) * in.height;
  auto log_luma = [&](const std::vector<double>& f, size_t p) {
    const double y = 0.2126 * f[p] + 0.7152 * f[hw + p] + 0.0722 * f[2 * hw + p];
    return std::log(in.eps + std::max(0.0, y));
  };
  const double floor2 = in.norm_floor_rms * in.norm_floor_rms * double(hw);
  double total = 0;
  for (auto [s, j] : in.pairs) {
    std::vector<double> E(hw, 0.0), D(hw);
    for (size_t p = 0; p < hw; ++p) {
      for (uint32_t k = s; k < j; ++k) E[p] += in.theta_pos * in.pos[k][p] - in.theta_neg * in.neg[k][p];
      D[p] = log_luma(in.frames[j], p) - log_luma(in.frames[s], p);
    }
    E = pool_plane(E, in.width, in.height, in.pool);
    D = pool_plane(D, in.width, in.height, in.pool);
    double ee = 0, dd = 0;
    for (size_t c = 0; c < E.size(); ++c) {
      ee += E[c] * E[c];
      dd += D[c] * D[c];
    }
    const double nE = std::sqrt(std::max(ee, floor2)), nD = std::sqrt(std::max(dd, floor2));
    double l = 0;
    for (size_t c = 0; c < E.size(); ++c) l += (E[c] / nE - D[c] / nD) * (E[c] / nE - D[c] / nD);
    total += l;
  }
  return in.pairs.empty() ? 0.0 : total / double(in.pairs.size());
}

}  // namespace evflow::reference
