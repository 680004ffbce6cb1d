// Signed images as the viewer's panels show them (events, warped events, predicted brightness
// changes): 0 is mid grey, positive values go to pure red, negative ones to pure blue.
// Header-only: the viewer test checks the panels against it.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace evflow::viewer {

// The colour scale of `values`: the 95th percentile of the nonzero |value|s (0 when all are 0).
inline double signed_scale(const std::vector<float>& values) {
  std::vector<float> mags;
  for (float s : values)
    if (s != 0 && std::isfinite(s)) mags.push_back(std::fabs(s));
  if (mags.empty()) return 0;
  const size_t q = size_t(0.95 * double(mags.size() - 1));
  std::nth_element(mags.begin(), mags.begin() + q, mags.end());
  return mags[q];
}

// Planar sRGB [3][n]: a value reaching k is pure red (255, 0, 0) or, negative, pure blue
// (0, 0, 255); 0 (and NaN) is grey (0.5 in sRGB, byte 128); in between the sRGB values are
// interpolated linearly: grey + (primary - grey) * |value| / k. k must be > 0.
inline std::vector<float> signed_colours(const std::vector<float>& values, double k) {
  const size_t n = values.size();
  const float grey = 0.5f;
  std::vector<float> rgb(3 * n, grey);
  for (size_t i = 0; i < n; ++i) {
    if (!(values[i] != 0) || !std::isfinite(values[i])) continue;
    const float a = float(std::min(1.0, std::fabs(values[i]) / k));
    float r = grey, g = grey, b = grey;
    if (values[i] > 0) {
      r = grey + (1.f - grey) * a;
      g = b = grey * (1.f - a);
    } else {
      b = grey + (1.f - grey) * a;
      r = g = grey * (1.f - a);
    }
    rgb[i] = r;
    rgb[n + i] = g;
    rgb[2 * n + i] = b;
  }
  return rgb;
}

}  // namespace evflow::viewer
