#include "io/image.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "io/atomic_file.h"
#include "io/image_codec.h"

namespace evflow::io {

namespace fs = std::filesystem;

float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : static_cast<float>(std::pow((double(v) + 0.055) / 1.055, 2.4));
}

float linear_to_srgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : static_cast<float>(1.055 * std::pow(double(v), 1.0 / 2.4) - 0.055);
}

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

void check_image(const fs::path& path, const Image& im) {
  if (im.channels != 1 && im.channels != 3 && im.channels != 4)
    fail(path, "cannot write an image with " + std::to_string(im.channels) + " channels (1, 3 or 4)");
  if (im.width == 0 || im.height == 0) fail(path, "cannot write an empty image");
  if (im.data.size() != size_t(im.width) * im.height * im.channels)
    fail(path, "image data has " + std::to_string(im.data.size()) + " values, expected " +
                   std::to_string(size_t(im.width) * im.height * im.channels));
}

void write_encoded(const fs::path& path, uint32_t width, uint32_t height, uint32_t channels, bool is_float,
                   const void* pixels) {
  write_file_atomic(
      path, [&](const fs::path& tmp) { codec::active::encode(tmp, path, width, height, channels, is_float, pixels); });
}

}  // namespace

Image read_image(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) fail(path, "image file is missing");
  const codec::Decoded d = codec::active::decode(path);
  const int nc = d.channels;
  const size_t npx = size_t(d.width) * size_t(d.height);
  const std::vector<float>& raw = d.values;
  const bool is_float = d.is_float;
  Image im(uint32_t(d.width), uint32_t(d.height), 3);
  // 8-bit files: a 256-entry table; other integer depths: the formula.
  float lut[256];
  const bool eight = d.eight_bit;
  if (eight)
    for (int i = 0; i < 256; ++i) lut[i] = srgb_to_linear(float(i) / 255.f);
  for (size_t i = 0; i < npx; ++i) {
    for (int c = 0; c < 3; ++c) {
      float v = raw[i * nc + std::min(c, nc >= 3 ? c : 0)];
      if (!is_float) {
        if (eight) {
          v = lut[std::clamp(int(std::lround(v * 255.f)), 0, 255)];
        } else {
          v = srgb_to_linear(v);
        }
      }
      im.data[i * 3 + c] = v;
    }
  }
  return im;
}

void write_png(const fs::path& path, const Image& im) {
  check_image(path, im);
  std::vector<uint8_t> px(im.data.size());
  for (size_t i = 0; i < px.size(); ++i) {
    float v = im.data[i];
    if (!(v > 0.f)) v = 0.f;  // also maps NaN to 0
    // alpha (4th channel) is stored linearly, colour is sRGB-encoded
    const bool alpha = im.channels == 4 && i % 4 == 3;
    float e = alpha ? std::min(v, 1.f) : linear_to_srgb(std::min(v, 1.f));
    px[i] = static_cast<uint8_t>(std::lround(e * 255.f));
  }
  write_encoded(path, im.width, im.height, im.channels, false, px.data());
}

void write_png8(const fs::path& path, uint32_t width, uint32_t height, uint32_t channels,
                const std::vector<uint8_t>& interleaved) {
  if (channels != 1 && channels != 3 && channels != 4)
    fail(path, "cannot write an image with " + std::to_string(channels) + " channels (1, 3 or 4)");
  if (width == 0 || height == 0) fail(path, "cannot write an empty image");
  if (interleaved.size() != size_t(width) * height * channels)
    fail(path, "image data has " + std::to_string(interleaved.size()) + " bytes, expected " +
                   std::to_string(size_t(width) * height * channels));
  write_encoded(path, width, height, channels, false, interleaved.data());
}

void write_exr(const fs::path& path, const Image& im) {
  check_image(path, im);
  write_encoded(path, im.width, im.height, im.channels, true, im.data.data());
}

void write_image(const fs::path& path, const Image& im) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".png") return write_png(path, im);
  if (ext == ".exr") return write_exr(path, im);
  fail(path, "unsupported image extension '" + ext + "' for writing (use .png or .exr)");
}

std::vector<float> planar_rgb(const Image& img) {
  const size_t hw = size_t(img.width) * img.height;
  std::vector<float> out(3 * hw);
  for (size_t i = 0; i < hw; ++i)
    for (uint32_t c = 0; c < 3; ++c) out[c * hw + i] = img.data[i * img.channels + std::min(c, img.channels - 1)];
  return out;
}

Image image_from_planar_rgb(const std::vector<float>& planar, uint32_t width, uint32_t height) {
  const size_t hw = size_t(width) * height;
  if (planar.size() < 3 * hw) throw std::invalid_argument("image_from_planar_rgb: fewer than 3 x H x W values");
  Image img;
  img.width = width;
  img.height = height;
  img.channels = 3;
  img.data.resize(3 * hw);
  for (size_t i = 0; i < hw; ++i)
    for (int c = 0; c < 3; ++c) img.data[i * 3 + c] = planar[c * hw + i];
  return img;
}

Image image_from_render(const std::vector<float>& planar_srgb, uint32_t width, uint32_t height) {
  Image img = image_from_planar_rgb(planar_srgb, width, height);
  for (float& x : img.data) x = srgb_to_linear(x);
  return img;
}

}  // namespace evflow::io
