// Synthetic Gaussian clouds for benchmarks and demos (not tests: those use tests/reference).
#pragma once
#include <cstdint>

#include "splat/gaussians.h"

namespace evflow {

// n Gaussians spread through the view frustum of `cam` at depths [2, 10], with screen-space
// sizes log-uniform in about [0.5, 6] px (like a trained scene), random orientations, opacity
// logits in [-2, 3] and SH coefficients of the given degree. Deterministic for a seed.
GaussianCloud synthetic_cloud(uint64_t seed, size_t n, int sh_degree, const Camera& cam);

}  // namespace evflow
