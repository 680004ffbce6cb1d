#include "metrics/srgb_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "io/image.h"

namespace evflow::metrics {

namespace {

uint8_t to_byte(float v) {
  if (!(v > 0.f)) return 0;  // NaN and negatives
  return uint8_t(std::lround(std::min(v, 1.f) * 255.f));
}

Image8 make(uint32_t w, uint32_t h, uint32_t c, size_t n) {
  if (size_t(w) * h * c != n)
    throw std::invalid_argument("metrics: " + std::to_string(n) + " values for a " + std::to_string(w) + "x" +
                                std::to_string(h) + "x" + std::to_string(c) + " image");
  Image8 im;
  im.width = w, im.height = h, im.channels = c;
  im.data.resize(n);
  return im;
}

void check_pair(const Image8& a, const Image8& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels || a.data.empty())
    throw std::invalid_argument("metrics: the images differ in size (" + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + "x" + std::to_string(a.channels) + " vs " +
                                std::to_string(b.width) + "x" + std::to_string(b.height) + "x" +
                                std::to_string(b.channels) + ") or are empty");
}

constexpr int kRadius = 5;  // 11 taps

std::array<double, 2 * kRadius + 1> gaussian_window() {
  std::array<double, 2 * kRadius + 1> w{};
  double sum = 0;
  for (int i = -kRadius; i <= kRadius; ++i) sum += w[i + kRadius] = std::exp(-0.5 * i * i / (1.5 * 1.5));
  for (double& x : w) x /= sum;
  return w;
}

// 'valid' separable filtering of a W x H plane: (W - 10) x (H - 10) out.
std::vector<double> filter_valid(const std::vector<double>& in, uint32_t W, uint32_t H) {
  static const auto w = gaussian_window();
  const uint32_t ow = W - 2 * kRadius, oh = H - 2 * kRadius;
  std::vector<double> tmp(size_t(ow) * H), out(size_t(ow) * oh);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < ow; ++x) {
      double s = 0;
      for (int k = 0; k <= 2 * kRadius; ++k) s += w[k] * in[size_t(y) * W + x + k];
      tmp[size_t(y) * ow + x] = s;
    }
  for (uint32_t y = 0; y < oh; ++y)
    for (uint32_t x = 0; x < ow; ++x) {
      double s = 0;
      for (int k = 0; k <= 2 * kRadius; ++k) s += w[k] * tmp[size_t(y + k) * ow + x];
      out[size_t(y) * ow + x] = s;
    }
  return out;
}

double ssim_plane(const uint8_t* a, const uint8_t* b, uint32_t W, uint32_t H) {
  const size_t n = size_t(W) * H;
  std::vector<double> x(n), y(n), xx(n), yy(n), xy(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = a[i], y[i] = b[i];
    xx[i] = x[i] * x[i], yy[i] = y[i] * y[i], xy[i] = x[i] * y[i];
  }
  const auto mx = filter_valid(x, W, H), my = filter_valid(y, W, H);
  const auto fxx = filter_valid(xx, W, H), fyy = filter_valid(yy, W, H), fxy = filter_valid(xy, W, H);
  const double C1 = (0.01 * 255) * (0.01 * 255), C2 = (0.03 * 255) * (0.03 * 255);
  double sum = 0;
  for (size_t i = 0; i < mx.size(); ++i) {
    const double vx = fxx[i] - mx[i] * mx[i], vy = fyy[i] - my[i] * my[i], cxy = fxy[i] - mx[i] * my[i];
    sum += ((2 * mx[i] * my[i] + C1) * (2 * cxy + C2)) / ((mx[i] * mx[i] + my[i] * my[i] + C1) * (vx + vy + C2));
  }
  return sum / double(mx.size());
}

}  // namespace

Image8 quantise_srgb(const std::vector<float>& planar_srgb, uint32_t width, uint32_t height, uint32_t channels) {
  Image8 im = make(width, height, channels, planar_srgb.size());
  for (size_t i = 0; i < planar_srgb.size(); ++i) im.data[i] = to_byte(planar_srgb[i]);
  return im;
}

Image8 encode_linear(const std::vector<float>& planar_linear, uint32_t width, uint32_t height, uint32_t channels) {
  Image8 im = make(width, height, channels, planar_linear.size());
  for (size_t i = 0; i < planar_linear.size(); ++i) {
    const float v = planar_linear[i];
    im.data[i] = to_byte(v > 0.f ? io::linear_to_srgb(std::min(v, 1.f)) : v);
  }
  return im;
}

double psnr(const Image8& a, const Image8& b) {
  check_pair(a, b);
  double se = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const double d = double(a.data[i]) - double(b.data[i]);
    se += d * d;
  }
  if (se == 0) return kPsnrIdentical;
  return 10.0 * std::log10(255.0 * 255.0 * double(a.data.size()) / se);
}

double psnr_srgb(const std::vector<float>& a, const std::vector<float>& b) {
  return psnr(quantise_srgb(a, uint32_t(a.size()), 1, 1), quantise_srgb(b, uint32_t(b.size()), 1, 1));
}

double ssim(const Image8& a, const Image8& b) {
  check_pair(a, b);
  if (a.width <= 2 * kRadius || a.height <= 2 * kRadius)
    throw std::invalid_argument("metrics: SSIM needs images of at least 11x11, got " + std::to_string(a.width) + "x" +
                                std::to_string(a.height));
  const size_t plane = size_t(a.width) * a.height;
  double sum = 0;
  for (uint32_t c = 0; c < a.channels; ++c)
    sum += ssim_plane(a.data.data() + c * plane, b.data.data() + c * plane, a.width, a.height);
  return sum / a.channels;
}

Scores score(const Image8& a, const Image8& b) { return {psnr(a, b), ssim(a, b)}; }

void write_png(const std::filesystem::path& path, const Image8& im) {
  const size_t plane = size_t(im.width) * im.height;
  std::vector<uint8_t> hwc(im.data.size());
  for (size_t i = 0; i < plane; ++i)
    for (uint32_t c = 0; c < im.channels; ++c) hwc[i * im.channels + c] = im.data[c * plane + i];
  io::write_png8(path, im.width, im.height, im.channels, hwc);
}

}  // namespace evflow::metrics
