// Image quality as the peers score it: on images encoded to sRGB, clamped to [0, 1] and
// quantised to 8 bits exactly as a saved PNG holds them. PSNR over all pixels and channels
// (peak 255); SSIM as Wang et al. 2004 (11x11 Gaussian window, sigma 1.5, K1 = 0.01,
// K2 = 0.03, population statistics, the mean over the pixels whose window lies inside the
// image, per channel, averaged over channels) -- what skimage's structural_similarity gives with
// gaussian_weights=True, use_sample_covariance=False, data_range=255.
// Images here are planar (c * H * W + y * W + x), the GPU's layout.
#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

namespace evflow::metrics {

// PSNR of two identical images (the MSE is 0): a finite cap, so that tables and JSON stay numbers.
inline constexpr double kPsnrIdentical = 100.0;

struct Image8 {
  uint32_t width = 0, height = 0, channels = 0;
  std::vector<uint8_t> data;  // planar
};

// sRGB-valued floats (renders: splat colours are sRGB) -> 8-bit: clamp to [0, 1] (NaN -> 0), round.
Image8 quantise_srgb(const std::vector<float>& planar_srgb, uint32_t width, uint32_t height, uint32_t channels);
// Linear-light floats (images as loaded, io::Image) -> sRGB encode -> 8-bit.
Image8 encode_linear(const std::vector<float>& planar_linear, uint32_t width, uint32_t height, uint32_t channels);

double psnr(const Image8& a, const Image8& b);
// PSNR of two sRGB-valued float images of the same size (any layout), each quantised as above.
double psnr_srgb(const std::vector<float>& a, const std::vector<float>& b);
double ssim(const Image8& a, const Image8& b);  // images at least 11 x 11

struct Scores {
  double psnr = 0, ssim = 0;
};
Scores score(const Image8& a, const Image8& b);

// The image as an 8-bit PNG holding exactly these values (atomic): re-scoring it with any tool
// gives the same figures.
void write_png(const std::filesystem::path& path, const Image8& image);

}  // namespace evflow::metrics
