// Double-precision CPU reference of the warped-event loss (engine/loss/warped_event_loss.h).
#pragma once
#include <cstdint>
#include <vector>

namespace evflow::reference {

struct WarpedEventInputs {
  uint32_t width = 0, height = 0;
  std::vector<std::vector<double>> frames;  // planar RGB per virtual frame (3 * H * W)
  // Per interval i (frames i -> i + 1): the warped events M and the displacement dx, dy (H * W each).
  std::vector<std::vector<double>> m, dx, dy;
  double eps = 1e-3, norm_floor_rms = 1e-3;
  uint32_t pool = 1;  // M and P summed over pool x pool cells (cut at the border) before comparing
};

// (1 / intervals) * sum_i || M_i / nM - P_i / nP ||^2 over interior pixels, P_i = -(grad L_{i+1} . d_i)
// by central differences, norms floored at sqrt(H W) * floor_rms.
double warped_event_loss(const WarpedEventInputs& in);

}  // namespace evflow::reference
