// The flow panels' pictures of one interval (Trainer::snapshot's FlowSnapshot): the flow as the
// colour wheel of `evflow flow` (flow/flow_colour.h), the warped events M_i and the predicted
// change P_i as signed images (signed_image.h), each on its own scale. Header-only: the viewer
// test checks the panels against it.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "flow/flow_colour.h"
#include "train/trainer.h"
#include "viewer/signed_image.h"

namespace evflow::viewer {

struct FlowImages {
  std::vector<float> flow;                 // planar sRGB [3][H][W]: the colour wheel
  double max_px = 1;                       // the length shown at full saturation
  std::vector<float> measured, predicted;  // planar sRGB signed images (empty without the warp term)
};

// The wheel saturates at the longest finite displacement (at least 1 pixel); M_i and P_i are
// each scaled by the 95th percentile of their nonzero magnitudes (the loss compares them
// normalised, so only their patterns matter).
inline FlowImages flow_images(const FlowSnapshot& f) {
  FlowImages im;
  const size_t hw = size_t(f.width) * f.height;
  for (size_t p = 0; p < hw && 2 * p + 1 < f.flow.size(); ++p) {
    const double len = std::hypot(f.flow[2 * p], f.flow[2 * p + 1]);
    if (std::isfinite(len)) im.max_px = std::max(im.max_px, len);
  }
  const std::vector<uint8_t> rgb = flow::flow_colour_wheel(f.flow, im.max_px);
  im.flow.assign(3 * hw, 0.0f);
  for (size_t p = 0; p < hw; ++p)
    for (size_t c = 0; c < 3; ++c) im.flow[c * hw + p] = float(rgb[3 * p + c]) / 255.0f;
  if (!f.warped) return im;
  for (auto [in, out] : {std::pair{&f.measured, &im.measured}, std::pair{&f.predicted, &im.predicted}}) {
    const double k = signed_scale(*in);
    *out = signed_colours(*in, k > 0 ? k : 1.0);
  }
  return im;
}

}  // namespace evflow::viewer
