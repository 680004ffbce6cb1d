#include "reference/nn_reference.h"

#include <cmath>

namespace evflow::ref {

NnTensor nn_conv2d(const NnTensor& x, const std::vector<double>& weight, const std::vector<double>& bias,
                   uint32_t out_c, uint32_t ksize, uint32_t stride) {
  const int pad = int(ksize / 2);
  NnTensor y(out_c, (x.h + stride - 1) / stride, (x.w + stride - 1) / stride);
  for (uint32_t co = 0; co < out_c; ++co)
    for (uint32_t oy = 0; oy < y.h; ++oy)
      for (uint32_t ox = 0; ox < y.w; ++ox) {
        double s = bias[co];
        for (uint32_t ci = 0; ci < x.c; ++ci)
          for (uint32_t ky = 0; ky < ksize; ++ky)
            for (uint32_t kx = 0; kx < ksize; ++kx) {
              const int iy = int(oy * stride + ky) - pad, ix = int(ox * stride + kx) - pad;
              if (iy < 0 || ix < 0 || iy >= int(x.h) || ix >= int(x.w)) continue;
              s += weight[((size_t(co) * x.c + ci) * ksize + ky) * ksize + kx] * x.at(ci, uint32_t(iy), uint32_t(ix));
            }
        y.at(co, oy, ox) = s;
      }
  return y;
}

NnTensor nn_relu(const NnTensor& x) {
  NnTensor y = x;
  for (double& v : y.v) v = v > 0 ? v : 0.0;
  return y;
}

NnTensor nn_sigmoid(const NnTensor& x) {
  NnTensor y = x;
  for (double& v : y.v) v = 1.0 / (1.0 + std::exp(-v));
  return y;
}

NnTensor nn_upsample(const NnTensor& x, uint32_t out_h, uint32_t out_w) {
  NnTensor y(x.c, out_h, out_w);
  for (uint32_t c = 0; c < x.c; ++c)
    for (uint32_t v = 0; v < out_h; ++v)
      for (uint32_t u = 0; u < out_w; ++u) y.at(c, v, u) = x.at(c, v / 2, u / 2);
  return y;
}

std::vector<double> nn_central_differences(std::vector<double>& v, const std::function<double()>& f, double h) {
  std::vector<double> g(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    const double keep = v[i];
    v[i] = keep + h;
    const double up = f();
    v[i] = keep - h;
    const double down = f();
    v[i] = keep;
    g[i] = (up - down) / (2 * h);
  }
  return g;
}

double nn_dot(const NnTensor& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t i = 0; i < a.v.size(); ++i) s += a.v[i] * b[i];
  return s;
}

}  // namespace evflow::ref
