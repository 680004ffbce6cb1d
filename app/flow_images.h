// Pictures of flow for `evflow flow`: the colour wheel (hue = direction, saturation = speed) and
// images of events normalised to 8 bits.
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::app {

// H * W * 3 bytes: hue from the direction of (u, v), saturation |(u, v)| / max_px (clamped),
// value 1; NaN flows are black.
std::vector<uint8_t> flow_colour_wheel(const std::vector<float>& flow, double max_px);
// H * W bytes: v / scale, clamped to [0, 1] (white = scale events or more).
std::vector<uint8_t> grey_image(const std::vector<float>& v, double scale);
// The variance of an image's values.
double image_variance(const std::vector<float>& v);

}  // namespace evflow::app
