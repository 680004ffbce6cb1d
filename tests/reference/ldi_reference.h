// Double-precision CPU reference of the learnable double integral (engine/ldi): the event
// tensors P(.) from the bin definitions in engine/ldi/event_bins.h (by time, not by index), the
// network (nn_reference), the double integral E and the sharp frames C = B / E.
#pragma once
#include <cstdint>
#include <vector>

#include "reference/nn_reference.h"

namespace evflow::ref {

struct LdiEvent {
  double t;
  uint32_t x, y;
  int p;  // +1 or -1
};

struct LdiCrop {
  uint32_t x = 0, y = 0, w = 0, h = 0;
};

// The 32-channel tensor of the side before (before = true) or after t_i of the window [t0, t1).
NnTensor ldi_side_tensor(const std::vector<LdiEvent>& events, double t0, double t1, double t_i, bool before,
                         const LdiCrop& crop);

struct LdiNet {
  std::vector<uint32_t> widths;
  std::vector<std::vector<double>> weight, bias;  // per layer, [out][in][3][3] and [out]
};
NnTensor ldi_net_forward(const LdiNet& net, const NnTensor& x);

double ldi_softplus(double x);
inline constexpr double kLdiRefFloor = double(1e-3f);

struct LdiFrames {
  std::vector<NnTensor> integral;  // per frame, 1 x h x w
  std::vector<NnTensor> frames;    // per frame, 3 x h x w
};
// Frames at `times` over the crop with the blurry crop (3 x h x w, linear).
LdiFrames ldi_frames(const LdiNet& net, const std::vector<LdiEvent>& events, double t0, double t1,
                     const std::vector<double>& times, const LdiCrop& crop, const NnTensor& blurry);

}  // namespace evflow::ref
