#include "reference/ssim_reference.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace evflow::reference {

namespace {
constexpr int kR = 5;
constexpr double kC1 = 0.01 * 0.01;
constexpr double kC2 = 0.03 * 0.03;

double ssim_from_moments(double ma, double mb, double maa, double mbb, double mab) {
  const double saa = maa - ma * ma, sbb = mbb - mb * mb, sab = mab - ma * mb;
  return (2 * ma * mb + kC1) * (2 * sab + kC2) / ((ma * ma + mb * mb + kC1) * (saa + sbb + kC2));
}
}  // namespace

const std::vector<double>& ssim_taps() {
  static const std::vector<double> g = [] {
    std::vector<double> w(2 * kR + 1);
    double s = 0;
    for (int k = -kR; k <= kR; ++k) s += w[k + kR] = std::exp(-double(k * k) / (2 * 1.5 * 1.5));
    for (auto& v : w) v /= s;
    return w;
  }();
  return g;
}

std::vector<double> ssim_map(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d) {
  const auto& g = ssim_taps();
  const size_t n = d.count();
  // Five moment images, horizontal pass then vertical pass, zero padding.
  std::vector<double> src[5], h[5], v[5];
  for (int m = 0; m < 5; ++m) src[m].resize(n), h[m].assign(n, 0.0), v[m].assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    src[0][i] = a[i], src[1][i] = b[i], src[2][i] = a[i] * a[i], src[3][i] = b[i] * b[i], src[4][i] = a[i] * b[i];
  }
  for (int c = 0; c < d.channels; ++c)
    for (int y = 0; y < d.height; ++y)
      for (int x = 0; x < d.width; ++x)
        for (int k = -kR; k <= kR; ++k) {
          const int xx = x + k;
          if (xx < 0 || xx >= d.width) continue;
          for (int m = 0; m < 5; ++m) h[m][d.index(c, y, x)] += g[k + kR] * src[m][d.index(c, y, xx)];
        }
  for (int c = 0; c < d.channels; ++c)
    for (int y = 0; y < d.height; ++y)
      for (int x = 0; x < d.width; ++x)
        for (int k = -kR; k <= kR; ++k) {
          const int yy = y + k;
          if (yy < 0 || yy >= d.height) continue;
          for (int m = 0; m < 5; ++m) v[m][d.index(c, y, x)] += g[k + kR] * h[m][d.index(c, yy, x)];
        }
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = ssim_from_moments(v[0][i], v[1][i], v[2][i], v[3][i], v[4][i]);
  return out;
}

double ssim_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d) {
  const auto m = ssim_map(a, b, d);
  double s = 0;
  for (double v : m) s += v;
  return s / double(m.size());
}

double ssim_pixel(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x) {
  const auto& g = ssim_taps();
  double m[5] = {0, 0, 0, 0, 0};
  for (int dy = -kR; dy <= kR; ++dy)
    for (int dx = -kR; dx <= kR; ++dx) {
      const int yy = y + dy, xx = x + dx;
      if (yy < 0 || yy >= d.height || xx < 0 || xx >= d.width) continue;
      const double w = g[dy + kR] * g[dx + kR];
      const double va = a[d.index(c, yy, xx)], vb = b[d.index(c, yy, xx)];
      m[0] += w * va, m[1] += w * vb, m[2] += w * va * va, m[3] += w * vb * vb, m[4] += w * va * vb;
    }
  return ssim_from_moments(m[0], m[1], m[2], m[3], m[4]);
}

double ssim_local_sum(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y,
                      int x) {
  double s = 0;
  for (int py = std::max(0, y - kR); py <= std::min(d.height - 1, y + kR); ++py)
    for (int px = std::max(0, x - kR); px <= std::min(d.width - 1, x + kR); ++px) s += ssim_pixel(a, b, d, c, py, px);
  return s;
}

double l1_mean(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += std::abs(a[i] - b[i]);
  return s / double(a.size());
}

double mse(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return s / double(a.size());
}

double psnr(const std::vector<double>& a, const std::vector<double>& b) { return -10.0 * std::log10(mse(a, b)); }

double blend_loss(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, double lambda) {
  return (1 - lambda) * l1_mean(a, b) + lambda * (1 - ssim_mean(a, b, d));
}

double fd_ssim_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x,
                    double h) {
  std::vector<double> p = a;
  const size_t i = d.index(c, y, x);
  p[i] = a[i] + h;
  const double up = ssim_local_sum(p, b, d, c, y, x);
  p[i] = a[i] - h;
  const double down = ssim_local_sum(p, b, d, c, y, x);
  return (up - down) / (2 * h) / double(d.count());
}

double fd_l1_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x,
                  double h) {
  const size_t i = d.index(c, y, x);
  return (std::abs(a[i] + h - b[i]) - std::abs(a[i] - h - b[i])) / (2 * h) / double(d.count());
}

double fd_blend_loss(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, double lambda,
                     int c, int y, int x, double h) {
  return (1 - lambda) * fd_l1_mean(a, b, d, c, y, x, h) - lambda * fd_ssim_mean(a, b, d, c, y, x, h);
}

}  // namespace evflow::reference
