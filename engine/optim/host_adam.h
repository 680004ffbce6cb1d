// Adam for a handful of double parameters on the host (camera trajectories, pose deltas):
// beta1 0.9, beta2 0.999, eps 1e-15, bias-corrected with the 1-based step count.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace evflow {

inline void host_adam_step(double* x, const double* grad, double* exp_avg, double* exp_avg_sq, size_t n, uint64_t step,
                           double lr) {
  const double b1 = 0.9, b2 = 0.999, eps = 1e-15;
  const double c1 = 1 - std::pow(b1, double(step)), c2 = 1 - std::pow(b2, double(step));
  for (size_t k = 0; k < n; ++k) {
    exp_avg[k] = b1 * exp_avg[k] + (1 - b1) * grad[k];
    exp_avg_sq[k] = b2 * exp_avg_sq[k] + (1 - b2) * grad[k] * grad[k];
    x[k] -= lr * (exp_avg[k] / c1) / (std::sqrt(exp_avg_sq[k] / c2) + eps);
  }
}

}  // namespace evflow
