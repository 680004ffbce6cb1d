// The colour wheel that pictures optical flow (`evflow flow`'s PNGs, the viewer's flow panel):
// hue = the direction of (u, v), saturation = its length.
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::flow {

// H * W * 3 bytes (RGB) from H * W * 2 flow values (u, v interleaved): hue (degrees) =
// atan2(v, u) + 180 (so +u, to the right, is cyan, -u red), saturation |(u, v)| / max_px
// (clamped to 1), value 1: no motion is white. NaN flows are black.
std::vector<uint8_t> flow_colour_wheel(const std::vector<float>& flow, double max_px);

}  // namespace evflow::flow
