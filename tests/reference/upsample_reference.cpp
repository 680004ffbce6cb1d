#include "reference/upsample_reference.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace evflow::reference {

namespace {

struct Field {
  const std::vector<float>& flow;
  uint32_t W, H, interval;
  float dx(int x, int y) const { return flow[(2 * size_t(interval)) * W * H + size_t(y) * W + size_t(x)]; }
  float dy(int x, int y) const { return flow[(2 * size_t(interval) + 1) * W * H + size_t(y) * W + size_t(x)]; }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < int(W) && y < int(H); }
};

// Sub-frame value of channel plane `f` at target (x, y), fraction s.
double sub_frame(const Field& g, const std::vector<double>& f, int x, int y, float s, int reach) {
  const float px = float(x) - s * g.dx(x, y), py = float(y) - s * g.dy(x, y);
  const float fx = std::floor(px), fy = std::floor(py), ax = px - fx, ay = py - fy;
  double sum = 0, total = 0;
  for (int k = 0; k < 4; ++k) {
    const int qx = int(fx) + (k & 1), qy = int(fy) + (k >> 1);
    if (!g.inside(qx, qy)) continue;
    const int cx = qx + int(std::nearbyint(s * g.dx(qx, qy))), cy = qy + int(std::nearbyint(s * g.dy(qx, qy)));
    if (std::max(std::abs(x - cx), std::abs(y - cy)) > reach) continue;
    const double w = double((k & 1) ? ax : 1.0f - ax) * double((k >> 1) ? ay : 1.0f - ay);
    sum += w * f[size_t(qy) * g.W + size_t(qx)];
    total += w;
  }
  return total > 0 ? sum / total : f[size_t(y) * g.W + size_t(x)];
}

}  // namespace

std::vector<double> upsampled_mean(const std::vector<std::vector<double>>& frames, const std::vector<float>& flow,
                                   uint32_t W, uint32_t H, uint32_t M, int reach) {
  const size_t hw = size_t(W) * H, F = frames.size();
  const double count = double(F + (F - 1) * (M - 1));
  std::vector<double> mean(3 * hw, 0.0);
  for (const auto& f : frames)
    for (size_t k = 0; k < 3 * hw; ++k) mean[k] += f[k] / count;
  for (uint32_t i = 0; i + 1 < F; ++i) {
    const Field g{flow, W, H, i};
    for (uint32_t c = 0; c < 3; ++c) {
      const std::vector<double> plane(frames[i].begin() + c * hw, frames[i].begin() + (c + 1) * hw);
      for (uint32_t m = 1; m < M; ++m)
        for (int y = 0; y < int(H); ++y)
          for (int x = 0; x < int(W); ++x)
            mean[c * hw + size_t(y) * W + size_t(x)] += sub_frame(g, plane, x, y, float(m) / float(M), reach) / count;
    }
  }
  return mean;
}

}  // namespace evflow::reference
