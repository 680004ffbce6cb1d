// Deterministic random test scenes for the splat rasterizer tests (identical on every platform:
// std::mt19937_64 with hand-written uniform / Box-Muller normal distributions).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "splat/gaussians.h"

namespace evflow::reference {

// A hard scene of n Gaussians for `cam`: most in front of the camera within the view (log-uniform
// screen sizes of about 0.6..5 px), ~12% with their mean within a pixel of a 16-px tile border,
// ~3% behind the camera, ~3% beyond the image edges, ~5% very thin (one log-scale 6 below the
// others), ~3% very large (sigma 8..20% of the image size), opacity logits uniform in [-3, 4],
// random unnormalised quaternions (norm 0.6..1.6), SH DC ~ N(0, 0.5), higher SH ~ N(0, 0.1).
// Each special category has at least one member when n >= 20.
GaussianCloud random_scene(uint64_t seed, size_t n, int sh_degree, const Camera& cam);

// A look-at camera with a 60 degree vertical field of view, an oblique (non-trivial) rotation and
// the principal point at the image centre; the scene of random_scene lies 1.5..7 units ahead.
Camera test_camera(uint32_t width, uint32_t height);

// n values uniform in [-1, 1].
std::vector<float> random_weights(uint64_t seed, size_t n);

}  // namespace evflow::reference
