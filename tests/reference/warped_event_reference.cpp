#include "reference/warped_event_reference.h"

#include "reference/event_reference.h"

#include <algorithm>
#include <cmath>

namespace evflow::reference {

double warped_event_loss(const WarpedEventInputs& in) {
  const size_t W = in.width, H = in.height, hw = W * H;
  const double floor2 = in.norm_floor_rms * in.norm_floor_rms * double(hw);
  double total = 0;
  for (size_t i = 0; i < in.m.size(); ++i) {
    const std::vector<double>& f = in.frames[i + 1];
    auto L = [&](size_t x, size_t y) {
      const size_t p = y * W + x;
      return std::log(in.eps + std::max(0.0, 0.2126 * f[p] + 0.7152 * f[hw + p] + 0.0722 * f[2 * hw + p]));
    };
    std::vector<double> M(hw, 0.0), P(hw, 0.0);
    for (size_t y = 1; y + 1 < H; ++y)
      for (size_t x = 1; x + 1 < W; ++x) {
        const size_t p = y * W + x;
        const double lx = 0.5 * (L(x + 1, y) - L(x - 1, y)), ly = 0.5 * (L(x, y + 1) - L(x, y - 1));
        M[p] = in.m[i][p];
        P[p] = -(lx * in.dx[i][p] + ly * in.dy[i][p]);
      }
    M = pool_plane(M, in.width, in.height, in.pool);
    P = pool_plane(P, in.width, in.height, in.pool);
    double mm = 0, pp = 0;
    for (size_t c = 0; c < M.size(); ++c) mm += M[c] * M[c], pp += P[c] * P[c];
    const double nM = std::sqrt(std::max(mm, floor2)), nP = std::sqrt(std::max(pp, floor2));
    for (size_t c = 0; c < M.size(); ++c) total += (M[c] / nM - P[c] / nP) * (M[c] / nM - P[c] / nP);
  }
  return in.m.empty() ? 0.0 : total / double(in.m.size());
}

}  // namespace evflow::reference
