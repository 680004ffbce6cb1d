// The residual panel's pictures of one training view (Trainer::snapshot's ResidualSnapshot): per
// non-middle virtual frame i, the residual prior's R(t_i) beside the renders' F_i - F_N, each as
// the signed image (signed_image.h) of its luminance in linear light (Rec. 709 weights). All on
// one colour scale, the prior's: a render residual that matches the prior looks the same, and
// the scale does not change while training runs. Header-only: the viewer test checks the panel
// against it.
#pragma once
#include <vector>

#include "train/trainer.h"
#include "viewer/signed_image.h"

namespace evflow::viewer {

struct ResidualImages {
  std::vector<std::vector<float>> tiles;  // planar sRGB, in pairs: prior_i, render_i, for each frame i in order
  double scale = 1;                       // the magnitude shown as pure red / blue
};

// Planar RGB [3][n] -> luminance [n].
inline std::vector<float> luminance(const std::vector<float>& rgb) {
  const size_t n = rgb.size() / 3;
  std::vector<float> y(n);
  for (size_t p = 0; p < n; ++p) y[p] = 0.2126f * rgb[p] + 0.7152f * rgb[n + p] + 0.0722f * rgb[2 * n + p];
  return y;
}

// The scale: the 95th percentile of the nonzero |luminance| of all the prior's residuals; the
// renders' when the prior is zero everywhere; 1 when both are.
inline ResidualImages residual_images(const ResidualSnapshot& r) {
  std::vector<std::vector<float>> prior, renders;
  std::vector<float> all_prior, all_renders;
  for (size_t k = 0; k < r.prior.size() && k < r.renders.size(); ++k) {
    prior.push_back(luminance(r.prior[k]));
    renders.push_back(luminance(r.renders[k]));
    all_prior.insert(all_prior.end(), prior.back().begin(), prior.back().end());
    all_renders.insert(all_renders.end(), renders.back().begin(), renders.back().end());
  }
  ResidualImages im;
  im.scale = signed_scale(all_prior);
  if (!(im.scale > 0)) im.scale = signed_scale(all_renders);
  if (!(im.scale > 0)) im.scale = 1;
  for (size_t k = 0; k < prior.size(); ++k) {
    im.tiles.push_back(signed_colours(prior[k], im.scale));
    im.tiles.push_back(signed_colours(renders[k], im.scale));
  }
  return im;
}

}  // namespace evflow::viewer
