// Double-precision CPU reference of the sRGB transfer function (IEC 61966-2-1), as the shaders
// apply it (shaders/common/srgb.glsl): the decode from sRGB-encoded values to linear light and its
// derivative.
#pragma once
#include <cmath>

namespace evflow::reference {

inline double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

inline double srgb_decode_deriv(double v) {
  return v <= 0.04045 ? 1.0 / 12.92 : (2.4 / 1.055) * std::pow((v + 0.055) / 1.055, 1.4);
}

}  // namespace evflow::reference
