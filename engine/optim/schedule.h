// Learning-rate schedules.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace evflow {

// Log-linear (exponential) decay from lr_init at step 0 to lr_final at max_steps, constant
// after; with delay_steps > 0 the rate is first scaled by a warm-up factor rising from
// delay_mult to 1 along a quarter sine (3DGS get_expon_lr_func, used for the means).
struct ExponentialDecay {
  double lr_init = 0.0;
  double lr_final = 0.0;
  uint64_t max_steps = 1;
  double delay_mult = 1.0;
  uint64_t delay_steps = 0;

  double operator()(uint64_t step) const {
    if (lr_init == 0.0 && lr_final == 0.0) return 0.0;
    double delay = 1.0;
    if (delay_steps > 0) {
      const double u = std::clamp(double(step) / double(delay_steps), 0.0, 1.0);
      delay = delay_mult + (1.0 - delay_mult) * std::sin(0.5 * M_PI * u);
    }
    const double t = max_steps ? std::clamp(double(step) / double(max_steps), 0.0, 1.0) : 1.0;
    return delay * std::exp(std::log(lr_init) * (1.0 - t) + std::log(lr_final) * t);
  }
};

}  // namespace evflow
