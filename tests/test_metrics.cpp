// The yardstick: PSNR / SSIM on 8-bit sRGB images (metrics/srgb_metrics.h), against values
// computed independently (scikit-image, tests/reference/srgb_metrics_reference.py) and by hand.
#include <catch2/catch.hpp>

#include <cmath>

#include "io/image.h"
#include "metrics/srgb_metrics.h"

using namespace evflow;

namespace {

constexpr uint32_t W = 40, H = 32, C = 3;

// The reference script's images, planar.
metrics::Image8 procedural(int which) {
  metrics::Image8 im;
  im.width = W, im.height = H, im.channels = C;
  im.data.resize(size_t(W) * H * C);
  for (uint32_t c = 0; c < C; ++c)
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < W; ++x) {
        const int a = int((x * 7 + y * 13 + c * 31 + (x * y) % 17) % 256);
        int v = a;
        if (which == 1) v = std::clamp(a + int((x * 3 + y * 5 + c) % 11) - 5, 0, 255);
        if (which == 2) v = std::clamp(a / 2 + 40 + int((x + 2 * y + 3 * c) % 7) * 9, 0, 255);
        im.data[(size_t(c) * H + y) * W + x] = uint8_t(v);
      }
  return im;
}

}  // namespace

TEST_CASE("metrics: PSNR and SSIM match scikit-image on 8-bit images", "[metrics]") {
  const auto a = procedural(0), b = procedural(1), d = procedural(2);
  // skimage.metrics: peak_signal_noise_ratio(data_range=255), structural_similarity(gaussian_weights=True,
  // sigma=1.5, use_sample_covariance=False, data_range=255, channel_axis=-1).
  CHECK(metrics::psnr(a, b) == Approx(38.1915068558).epsilon(1e-9));
  CHECK(metrics::ssim(a, b) == Approx(0.9941783937).epsilon(1e-8));
  CHECK(metrics::psnr(a, d) == Approx(15.8655516686).epsilon(1e-9));
  CHECK(metrics::ssim(a, d) == Approx(0.6096268129).epsilon(1e-8));
  // Symmetric.
  CHECK(metrics::ssim(d, a) == Approx(metrics::ssim(a, d)).epsilon(1e-12));
}

TEST_CASE("metrics: hand-worked cases and the 8-bit encoding a PNG holds", "[metrics]") {
  const auto a = procedural(0);
  CHECK(metrics::psnr(a, a) == metrics::kPsnrIdentical);
  CHECK(metrics::ssim(a, a) == Approx(1.0).epsilon(1e-12));
  // Every value one level up (none is 255 after the shift below): MSE = 1, PSNR = 20 log10(255).
  metrics::Image8 lo = a, hi = a;
  for (auto& v : lo.data) v = uint8_t(v / 2);
  for (size_t i = 0; i < hi.data.size(); ++i) hi.data[i] = uint8_t(lo.data[i] + 1);
  CHECK(metrics::psnr(lo, hi) == Approx(20 * std::log10(255.0)).epsilon(1e-12));
  // A constant image against a constant image: SSIM = (2 m1 m2 + C1) / (m1^2 + m2^2 + C1).
  metrics::Image8 c1 = a, c2 = a;
  std::fill(c1.data.begin(), c1.data.end(), uint8_t(100));
  std::fill(c2.data.begin(), c2.data.end(), uint8_t(120));
  const double K1 = (0.01 * 255) * (0.01 * 255);
  CHECK(metrics::ssim(c1, c2) == Approx((2 * 100.0 * 120 + K1) / (100.0 * 100 + 120.0 * 120 + K1)).epsilon(1e-12));

  // sRGB-valued floats: clamp, NaN -> 0, round half up as write_png does.
  const auto q = metrics::quantise_srgb({0.5f, -0.1f, std::nanf(""), 2.f, 1.f / 255.f, 0.f}, 6, 1, 1);
  CHECK(std::vector<int>(q.data.begin(), q.data.end()) == std::vector<int>{128, 0, 0, 255, 1, 0});
  // Linear floats: encoded first; the same bytes as io::write_png writes.
  const auto e = metrics::encode_linear({0.5f, 0.0031308f, 1.f, 0.214f}, 4, 1, 1);
  CHECK(std::vector<int>(e.data.begin(), e.data.end()) == std::vector<int>{188, 10, 255, 127});
  // An 8-bit image decoded to linear (as images load) encodes back to the same bytes.
  std::vector<float> lin(256);
  for (int i = 0; i < 256; ++i) lin[i] = io::srgb_to_linear(i / 255.f);
  const auto back = metrics::encode_linear(lin, 256, 1, 1);
  for (int i = 0; i < 256; ++i) CHECK(int(back.data[i]) == i);

  // Bad input.
  metrics::Image8 small = a;
  small.width = 10, small.height = 96;
  CHECK_THROWS_WITH(metrics::ssim(small, small), Catch::Contains("11x11"));
  CHECK_THROWS_WITH(metrics::psnr(a, small), Catch::Contains("differ"));
  CHECK_THROWS_WITH(metrics::quantise_srgb({0.f, 1.f}, 3, 1, 1), Catch::Contains("2 values"));
}
