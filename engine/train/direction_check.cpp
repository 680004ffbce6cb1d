#include "train/direction_check.h"

#include <cmath>
#include <vector>

namespace evflow {

DirectionCheck::DirectionCheck(gpu::Context& ctx, EventLoss& events, uint32_t until_step, double margin)
    : events_(events), until_step_(until_step), margin_(margin), scores_(ctx, 8, "direction_check_scores") {}

void DirectionCheck::score_reversed_next() { events_.score_reversed_next(scores_, 1); }

void DirectionCheck::keep_forward(gpu::Commands& cmd) {
  cmd.copy(events_.value_buffer(), scores_, 4, uint64_t(events_.value_offset()) * 4, 0);
}

bool DirectionCheck::prefers_reversed() const {
  const std::vector<float> v = scores_.read<float>(2);
  return prefers(v[0], v[1], margin_);
}

bool DirectionCheck::prefers(double forward, double reversed, double margin) {
  return std::isfinite(forward) && std::isfinite(reversed) && reversed < forward * (1.0 - margin);
}

}  // namespace evflow
