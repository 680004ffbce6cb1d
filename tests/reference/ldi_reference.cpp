#include "reference/ldi_reference.h"

#include <algorithm>
#include <cmath>

namespace evflow::ref {

NnTensor ldi_side_tensor(const std::vector<LdiEvent>& events, double t0, double t1, double t_i, bool before,
                         const LdiCrop& crop) {
  NnTensor out(32, crop.h, crop.w);
  const double len = before ? t_i - t0 : t1 - t_i;
  for (const LdiEvent& e : events) {
    if (e.x < crop.x || e.y < crop.y || e.x >= crop.x + crop.w || e.y >= crop.y + crop.h) continue;
    int bin = 0;
    bool positive = e.p > 0;
    if (before) {
      if (!(e.t >= t0 && e.t < t_i)) continue;
      // t_i - (k + 1) L / 16 <= t < t_i - k L / 16
      bin = std::min(15, int(std::floor(16.0 * (e.t - t0) / len)));
      bin = 15 - bin;
      positive = !positive;
    } else {
      if (!(e.t >= t_i && e.t < t1)) continue;
      bin = std::min(15, int(std::floor(16.0 * (e.t - t_i) / len)));
    }
    out.at(uint32_t(2 * bin + (positive ? 0 : 1)), e.y - crop.y, e.x - crop.x) += 1.0;
  }
  return out;
}

NnTensor ldi_net_forward(const LdiNet& net, const NnTensor& x) {
  NnTensor z = x;
  for (size_t i = 0; i + 1 < net.widths.size(); ++i) {
    z = nn_conv2d(z, net.weight[i], net.bias[i], net.widths[i + 1], 3, 1);
    if (i + 2 < net.widths.size()) z = nn_relu(z);
  }
  return z;
}

double ldi_softplus(double x) { return std::max(x, 0.0) + std::log1p(std::exp(-std::abs(x))); }

LdiFrames ldi_frames(const LdiNet& net, const std::vector<LdiEvent>& events, double t0, double t1,
                     const std::vector<double>& times, const LdiCrop& crop, const NnTensor& blurry) {
  LdiFrames out;
  for (double t_i : times) {
    const double w1 = (t_i - t0) / (t1 - t0), w2 = 1.0 - w1;
    NnTensor a(1, crop.h, crop.w), b(1, crop.h, crop.w);
    if (w1 != 0) a = ldi_net_forward(net, ldi_side_tensor(events, t0, t1, t_i, true, crop));
    if (w2 != 0) b = ldi_net_forward(net, ldi_side_tensor(events, t0, t1, t_i, false, crop));
    NnTensor e(1, crop.h, crop.w), c(3, crop.h, crop.w);
    for (size_t p = 0; p < e.v.size(); ++p) {
      e.v[p] = ldi_softplus(w1 * a.v[p] + w2 * b.v[p]) + kLdiRefFloor;
      for (uint32_t ch = 0; ch < 3; ++ch) c.v[ch * e.v.size() + p] = blurry.v[ch * e.v.size() + p] / e.v[p];
    }
    out.integral.push_back(e);
    out.frames.push_back(c);
  }
  return out;
}

}  // namespace evflow::ref
