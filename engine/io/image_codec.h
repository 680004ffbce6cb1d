// The image file codecs behind io/image.h: OpenImageIO (every format; the default build) and stb
// (PNG, JPEG and Radiance HDR, no EXR). A build with EVFLOW_IMAGE_IO=stb uses stb and compiles no
// OpenImageIO code (EVF_IMAGE_IO_STB defined); the default build has both, and uses OpenImageIO.
#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

namespace evflow::io::codec {

// A decoded file: interleaved values, integer files scaled to 0..1, float files as stored.
struct Decoded {
  int width = 0, height = 0, channels = 0;
  bool is_float = false;  // float/half data (EXR, HDR): linear, not to be sRGB-decoded
  bool eight_bit = false;
  std::vector<float> values;
};

// Each codec: decode throws std::runtime_error naming `path` when the file cannot be opened, is
// truncated or corrupt, or its format is not one the codec reads. encode writes `pixels` (8-bit, or
// 32-bit float when `is_float`) to `file` in the format its extension names, `shown` being the
// path errors name; it throws when the codec does not write that format.
namespace stb {
Decoded decode(const std::filesystem::path& path);
void encode(const std::filesystem::path& file, const std::filesystem::path& shown, uint32_t width, uint32_t height,
            uint32_t channels, bool is_float, const void* pixels);
}  // namespace stb
#ifndef EVF_IMAGE_IO_STB
namespace oiio {
Decoded decode(const std::filesystem::path& path);
void encode(const std::filesystem::path& file, const std::filesystem::path& shown, uint32_t width, uint32_t height,
            uint32_t channels, bool is_float, const void* pixels);
}  // namespace oiio
namespace active = oiio;  // the codec io/image.cpp uses
inline const char* backend_name() { return "OpenImageIO"; }
#else
namespace active = stb;
inline const char* backend_name() { return "stb"; }
#endif

}  // namespace evflow::io::codec
