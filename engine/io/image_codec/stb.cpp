// io/image_codec.h through stb (Debian's libstb): reads PNG (8/16-bit), JPEG, BMP, TGA and
// Radiance HDR; writes PNG and JPEG. EXR needs the OpenImageIO build and is refused by name.
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "io/image_codec.h"

namespace evflow::io::codec::stb {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

std::string lower_extension(const fs::path& path) {
  std::string e = path.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

[[noreturn]] void no_exr(const fs::path& path) {
  fail(path, "EXR images need an evflow built with OpenImageIO (this one was built with EVFLOW_IMAGE_IO=stb)");
}

// stbi_* allocations, freed with stbi_image_free.
template <class T>
using StbPixels = std::unique_ptr<T, void (*)(void*)>;

template <class T>
void copy_scaled(Decoded& d, const T* px, float scale) {
  d.values.resize(size_t(d.width) * size_t(d.height) * size_t(d.channels));
  for (size_t i = 0; i < d.values.size(); ++i) d.values[i] = float(px[i]) * scale;
}

// The whole file, read once: the format probes and the decoder all work on these bytes.
std::vector<stbi_uc> read_bytes(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::vector<stbi_uc> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (!f.good() && !f.eof()) fail(path, "cannot read image file");
  if (bytes.size() > size_t(std::numeric_limits<int>::max())) fail(path, "image file too large");
  return bytes;
}

}  // namespace

Decoded decode(const fs::path& path) {
  if (lower_extension(path) == ".exr") no_exr(path);
  const std::vector<stbi_uc> bytes = read_bytes(path);
  const stbi_uc* b = bytes.data();
  const int n = int(bytes.size());
  Decoded d;
  if (stbi_is_hdr_from_memory(b, n)) {
    StbPixels<float> px(stbi_loadf_from_memory(b, n, &d.width, &d.height, &d.channels, 0), stbi_image_free);
    if (!px) fail(path, std::string("cannot read image (truncated or corrupt?): ") + stbi_failure_reason());
    d.is_float = true;
    copy_scaled(d, px.get(), 1.f);
  } else if (stbi_is_16_bit_from_memory(b, n)) {
    StbPixels<stbi_us> px(stbi_load_16_from_memory(b, n, &d.width, &d.height, &d.channels, 0), stbi_image_free);
    if (!px) fail(path, std::string("cannot read image (truncated or corrupt?): ") + stbi_failure_reason());
    copy_scaled(d, px.get(), 1.f / 65535.f);
  } else {
    StbPixels<stbi_uc> px(stbi_load_from_memory(b, n, &d.width, &d.height, &d.channels, 0), stbi_image_free);
    if (!px) fail(path, std::string("cannot open image: ") + stbi_failure_reason());
    d.eight_bit = true;
    copy_scaled(d, px.get(), 1.f / 255.f);
  }
  if (d.width <= 0 || d.height <= 0 || d.channels <= 0) fail(path, "unsupported image geometry");
  return d;
}

void encode(const fs::path& file, const fs::path& shown, uint32_t width, uint32_t height, uint32_t channels,
            bool is_float, const void* pixels) {
  const std::string e = lower_extension(file);
  if (e == ".exr") no_exr(shown);
  if (is_float) fail(shown, "this build writes float images only as EXR, which needs OpenImageIO");
  const int w = int(width), h = int(height), c = int(channels);
  int ok = 0;
  if (e == ".png")
    ok = stbi_write_png(file.string().c_str(), w, h, c, pixels, w * c);
  else if (e == ".jpg" || e == ".jpeg")
    ok = stbi_write_jpg(file.string().c_str(), w, h, c, pixels, 95);
  else
    fail(shown, "no image writer for the extension '" + e + "' in this build (PNG and JPEG)");
  if (!ok) fail(shown, "cannot write image");
}

}  // namespace evflow::io::codec::stb
