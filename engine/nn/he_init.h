// He (Kaiming) initialisation, seeded and the same on every platform: values drawn from
// N(0, 2 / fan_in) by a 64-bit Mersenne Twister and the Box-Muller transform written here (the
// standard library's distributions differ between implementations).
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::nn {

std::vector<float> he_normal(uint64_t count, uint32_t fan_in, uint64_t seed);

}  // namespace evflow::nn
