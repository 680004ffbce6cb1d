// Double-precision CPU reference of the event loss (engine/loss/event_loss.h, paper Eq. 5).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

namespace evflow::reference {

struct EventLossInputs {
  uint32_t width = 0, height = 0;
  std::vector<std::vector<double>> frames;  // planar RGB per virtual frame (3 * H * W)
  // Per interval k (frames k -> k+1): positive and negative event counts per pixel (H * W each).
  std::vector<std::vector<int>> pos, neg;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;  // (s, j)
  double theta_pos = 0.2, theta_neg = 0.2, eps = 1e-3, norm_floor_rms = 1e-3;
  uint32_t pool = 1;  // E and D summed over pool x pool cells (cut at the border) before comparing
};

// Sums a W x H plane over cells of pool x pool pixels, row by row (the last cells cut at the border).
std::vector<double> pool_plane(const std::vector<double>& v, uint32_t width, uint32_t height, uint32_t pool);

// (1 / pairs) * sum over pairs of || E / nE - D / nD ||^2 over the pooling cells, norms floored at
// sqrt(H W) * floor_rms.
double event_loss(const EventLossInputs& in);

}  // namespace evflow::reference
