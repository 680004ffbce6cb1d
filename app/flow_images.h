// Pictures for `evflow flow`: images of events normalised to 8 bits (the flow's colour wheel is
// flow/flow_colour.h, shared with the viewer).
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::app {

// H * W bytes: v / scale, clamped to [0, 1] (white = scale events or more).
std::vector<uint8_t> grey_image(const std::vector<float>& v, double scale);
// The variance of an image's values.
double image_variance(const std::vector<float>& v);

}  // namespace evflow::app
