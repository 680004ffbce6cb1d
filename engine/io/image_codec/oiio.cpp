// io/image_codec.h through OpenImageIO: every format it reads; PNG, JPEG, EXR (zip) and more written.
#include <OpenImageIO/imageio.h>

#include <stdexcept>
#include <string>

#include "io/image_codec.h"

namespace evflow::io::codec::oiio {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

std::string oiio_error(const std::string& e) {
  std::string s = e.empty() ? OIIO::geterror() : e;
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s.empty() ? "unknown OpenImageIO error" : s;
}

}  // namespace

Decoded decode(const fs::path& path) {
  // Colour as stored, not multiplied by alpha (PNG's own convention, and stb's).
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) fail(path, "cannot open image: " + oiio_error(""));
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1)
    fail(path, "unsupported image geometry");
  Decoded d;
  d.width = spec.width;
  d.height = spec.height;
  d.channels = spec.nchannels;
  d.values.resize(size_t(d.width) * size_t(d.height) * size_t(d.channels));
  if (!in->read_image(0, 0, 0, d.channels, OIIO::TypeDesc::FLOAT, d.values.data())) {
    std::string e = in->geterror();
    fail(path, "cannot read image (truncated or corrupt?): " + oiio_error(e));
  }
  in->close();
  const auto base = spec.format.basetype;
  d.is_float = base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::DOUBLE;
  d.eight_bit = base == OIIO::TypeDesc::UINT8;
  return d;
}

void encode(const fs::path& file, const fs::path& shown, uint32_t width, uint32_t height, uint32_t channels,
            bool is_float, const void* pixels) {
  const OIIO::TypeDesc type = is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8;
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) fail(shown, "no image writer for this extension: " + oiio_error(""));
  OIIO::ImageSpec spec(int(width), int(height), int(channels), type);
  if (is_float) spec.attribute("compression", "zip");
  spec.attribute("oiio:UnassociatedAlpha", 1);  // colour written as given, not divided by alpha
  if (!out->open(file.string(), spec)) fail(shown, "cannot create image: " + oiio_error(out->geterror()));
  bool ok = out->write_image(type, pixels);
  std::string err = ok ? "" : out->geterror();
  ok = out->close() && ok;
  if (!ok) fail(shown, "cannot write image: " + oiio_error(err.empty() ? out->geterror() : err));
}

}  // namespace evflow::io::codec::oiio
