#include "nn/he_init.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace evflow::nn {

std::vector<float> he_normal(uint64_t count, uint32_t fan_in, uint64_t seed) {
  if (fan_in == 0) throw std::invalid_argument("he_normal: fan_in must be positive");
  std::mt19937_64 rng(seed);
  auto uniform = [&rng] { return (double(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); };  // (0, 1)
  const double sigma = std::sqrt(2.0 / fan_in);
  std::vector<float> v(count);
  for (uint64_t i = 0; i < count; i += 2) {
    const double r = std::sqrt(-2.0 * std::log(uniform())), a = 2.0 * M_PI * uniform();
    v[i] = float(sigma * r * std::cos(a));
    if (i + 1 < count) v[i + 1] = float(sigma * r * std::sin(a));
  }
  return v;
}

}  // namespace evflow::nn
