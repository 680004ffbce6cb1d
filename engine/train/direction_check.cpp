#include "train/direction_check.h"

#include <algorithm>
#include <cmath>

namespace evflow {

DirectionCheck::DirectionCheck(EventLoss& events, uint32_t until_step, double margin)
    : events_(events), until_step_(until_step), margin_(margin) {}

void DirectionCheck::score_reversed(gpu::Commands& cmd, ExposureFrames frames) {
  std::reverse(frames.rgb.begin(), frames.rgb.end());
  frames.grad.clear();
  cmd.submit();  // value slots recorded before (the image terms') are read after the next submit: keep them
  events_.record_value(cmd, frames);
  cmd.mark("direction check");
  cmd.submit();
  reversed_ = events_.value();
}

bool DirectionCheck::prefers_reversed(gpu::Commands& cmd) const {
  cmd.submit();
  return prefers(events_.value(), reversed_, margin_);
}

bool DirectionCheck::prefers(double forward, double reversed, double margin) {
  return std::isfinite(forward) && std::isfinite(reversed) && reversed < forward * (1.0 - margin);
}

}  // namespace evflow
