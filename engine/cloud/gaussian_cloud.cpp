#include "cloud/gaussian_cloud.h"

#include <cmath>
#include <stdexcept>

namespace evflow {

void GaussianCloud::resize(size_t n, int degree) {
  if (degree < 0 || degree > kMaxShDegree)
    throw std::invalid_argument("SH degree must be 0..3, got " + std::to_string(degree));
  sh_degree = degree;
  means.resize(n * 3);
  log_scales.resize(n * 3);
  quats.resize(n * 4);
  opacity_logits.resize(n);
  sh.resize(n * sh_coeff_count(degree) * 3);
}

void GaussianCloud::validate(const std::string& what) const {
  const size_t n = size();
  auto need = [&](const std::vector<float>& v, size_t per, const char* field) {
    if (v.size() != n * per)
      throw std::invalid_argument(what + ": field '" + field + "' has " + std::to_string(v.size()) +
                                  " values, expected " + std::to_string(n * per) + " for " + std::to_string(n) +
                                  " Gaussians");
    for (size_t i = 0; i < v.size(); ++i)
      if (!std::isfinite(v[i]))
        throw std::invalid_argument(what + ": field '" + field + "' of Gaussian " + std::to_string(i / per) +
                                    " is not finite");
  };
  if (sh_degree < 0 || sh_degree > kMaxShDegree) throw std::invalid_argument(what + ": SH degree must be 0..3");
  need(means, 3, "means");
  need(log_scales, 3, "log_scales");
  need(quats, 4, "quats");
  need(opacity_logits, 1, "opacity_logits");
  need(sh, coeffs() * 3, "sh");
}

}  // namespace evflow
