// Images on disk <-> linear float images in memory (OpenImageIO, or stb: io/image_codec.h).
#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

namespace evflow::io {

struct Image {
  uint32_t width = 0, height = 0, channels = 0;
  std::vector<float> data;  // interleaved HWC, linear intensity (nominally 0..1)

  Image() = default;
  Image(uint32_t w, uint32_t h, uint32_t c, float fill = 0.f)
      : width(w), height(h), channels(c), data(size_t(w) * h * c, fill) {}
  float& at(uint32_t x, uint32_t y, uint32_t c) { return data[(size_t(y) * width + x) * channels + c]; }
  float at(uint32_t x, uint32_t y, uint32_t c) const { return data[(size_t(y) * width + x) * channels + c]; }
  bool empty() const { return data.empty(); }
};

float srgb_to_linear(float v);  // IEC 61966-2-1 decode
float linear_to_srgb(float v);  // IEC 61966-2-1 encode

// Reads any file the codec reads (OpenImageIO: PNG, JPEG, EXR, TIFF, ...; stb: PNG, JPEG, HDR) as
// linear float RGB (3 channels):
// integer-valued files (8/16-bit) are sRGB-decoded; float/half files (EXR, HDR) are taken as
// linear. Grey is replicated to RGB; channels past the third (alpha) are dropped. Throws
// std::runtime_error naming the file on a missing, unreadable, truncated or unsupported file.
Image read_image(const std::filesystem::path& path);

// Writes by extension: .png -> 8-bit sRGB-encoded (values clamped to 0..1, rounded);
// .exr -> 32-bit float linear (exact; OpenImageIO build only). Accepts 1, 3 or 4 channels. Atomic (io/atomic_file.h).
void write_image(const std::filesystem::path& path, const Image& image);
void write_png(const std::filesystem::path& path, const Image& image);
void write_exr(const std::filesystem::path& path, const Image& image);
// Writes 8-bit values as they are (already sRGB-encoded), interleaved HWC. Atomic.
void write_png8(const std::filesystem::path& path, uint32_t width, uint32_t height, uint32_t channels,
                const std::vector<uint8_t>& interleaved);

// GPU images are planar (c * H * W + y * W + x). Planar RGB copy of an image (grey replicated),
// and an interleaved RGB image from planar data (values as they are; write_png clamps).
std::vector<float> planar_rgb(const Image& image);
Image image_from_planar_rgb(const std::vector<float>& planar, uint32_t width, uint32_t height);
// A splat render (planar RGB, sRGB-valued: splat colours are display-referred sRGB) as an image
// in memory (linear): every value decoded.
Image image_from_render(const std::vector<float>& planar_srgb, uint32_t width, uint32_t height);

}  // namespace evflow::io
