// The residual prior's data: training views simulated in procedural rooms (prior/training_rooms.h)
// with the simulator's own renderer, so the targets are exact. Per view: the network input (the
// blurry image as an 8-bit sRGB PNG holds it, back in linear RGB, and the event planes,
// prior/event_inputs.h) and the target R(t_i) = I(t_i) - I(t_N) of the sharp frames rendered at the
// 2N+1 virtual-frame times of the exposure; optionally the EDI baseline's residual (EDI frames with
// the nominal thresholds at t_i minus at t_N).
#pragma once
#include <cstdint>
#include <random>
#include <vector>

#include "gpu/context.h"

namespace evflow::prior {

struct SampleOptions {
  uint32_t width = 173, height = 130;
  uint32_t frames = 7;                       // 2N + 1
  int views_per_room = 8;                    // training views of each room's rig
  double blur_min_px = 4, blur_max_px = 10;  // each room's mean blur, drawn uniformly
};

struct PriorSample {
  uint32_t width = 0, height = 0;
  std::vector<float> input;         // in_channels x H x W (ResidualNetSpec)
  std::vector<float> target;        // out_channels x H x W: R(t_i) of the non-middle frames, RGB planes
  std::vector<float> edi_residual;  // the same layout; empty unless asked for
};

// The views of the rooms with the given seeds (room seed = simulator seed; the shake alternates
// smooth and jerk by room).
std::vector<PriorSample> simulate_samples(gpu::Context& ctx, const std::vector<uint64_t>& room_seeds,
                                          const SampleOptions& o, bool with_edi);

// A crop of `size` x `size` pixels at (x, y) of a sample's input and target planes.
struct Crop {
  std::vector<float> input, target;
};
Crop crop(const PriorSample& s, uint32_t x, uint32_t y, uint32_t size);

}  // namespace evflow::prior
