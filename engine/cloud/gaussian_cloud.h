// Host-side Gaussian splats: the parameter layout shared by io/, splat/, densify/, train/, tests.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace evflow {

inline constexpr int kMaxShDegree = 3;
inline constexpr int sh_coeff_count(int degree) { return (degree + 1) * (degree + 1); }

// Parameters are stored pre-activation (REFERENCE.md §1):
//   means          [N][3]  world position
//   log_scales     [N][3]  log of the standard deviations along the Gaussian's axes
//   quats          [N][4]  unnormalised rotation quaternion, (w, x, y, z)
//   opacity_logits [N]     sigmoid() gives opacity
//   sh             [N][K][3], K = (sh_degree+1)^2: coefficient k of channel c at (n*K + k)*3 + c;
//                  k = 0 is the DC term; colour = sum_k Y_k(dir) * sh[k] + 0.5, clamped at 0.
struct GaussianCloud {
  int sh_degree = 0;
  std::vector<float> means, log_scales, quats, opacity_logits, sh;

  size_t size() const { return opacity_logits.size(); }
  int coeffs() const { return sh_coeff_count(sh_degree); }
  void resize(size_t n, int degree);
  // Throws std::invalid_argument naming `what` when sizes disagree or a value is not finite.
  void validate(const std::string& what) const;
};

}  // namespace evflow
