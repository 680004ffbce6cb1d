#include "train/direction_check.h"

#include <algorithm>
#include <cmath>

namespace evflow {

DirectionCheck::DirectionCheck(gpu::Context& ctx, EventLoss& events, uint32_t until_step, double margin)
    : events_(events), until_step_(until_step), margin_(margin), reversed_(ctx, 4, "direction_check_reversed") {}

void DirectionCheck::record_reversed(gpu::Commands& cmd, ExposureFrames frames) {
  std::reverse(frames.rgb.begin(), frames.rgb.end());
  frames.grad.clear();
  events_.record_value(cmd, frames);
  cmd.copy(events_.value_buffer(), reversed_, 4, uint64_t(events_.value_offset()) * 4);
  cmd.mark("direction check");
}

bool DirectionCheck::prefers_reversed() const {
  return prefers(events_.value(), reversed_.read_one<float>(0), margin_);
}

bool DirectionCheck::prefers(double forward, double reversed, double margin) {
  return std::isfinite(forward) && std::isfinite(reversed) && reversed < forward * (1.0 - margin);
}

}  // namespace evflow
