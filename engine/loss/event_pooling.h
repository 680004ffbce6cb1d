// The pooling grid of the event losses: both sides of a normalised event loss are summed over
// square cells of `pool` x `pool` pixels before they are compared (pool 1: per pixel). The sum
// averages the per-pixel error of the events (threshold quantisation, threshold spread, noise)
// down by about `pool`, while an edge, which fires coherently along its length, keeps its sum.
// Cells in the last row and column are cut by the image border.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

namespace evflow {

constexpr uint32_t kMaxEventPool = 64;

inline uint64_t event_pool_cells(uint32_t width, uint32_t height, uint32_t pool) {
  return uint64_t((width + pool - 1) / pool) * ((height + pool - 1) / pool);
}

inline void check_event_pool(uint32_t pool, const char* who) {
  if (pool < 1 || pool > kMaxEventPool)
    throw std::invalid_argument(std::string(who) + ": pool must be in 1.." + std::to_string(kMaxEventPool) + ", got " +
                                std::to_string(pool));
}

}  // namespace evflow
