// The time direction of an exposure trajectory. The blur loss cannot tell a trajectory from its
// time reversal; the events can. Until `until_step`, each step also scores the time-reversed
// frame order with the event loss; when that scores lower than the forward order by the fraction
// `margin` of the forward order's value (a relative margin: the normalised loss starts near 2,
// where both orders of a half-formed trajectory score alike, and falls as the model fits),
// the view's trajectory is to be flipped (and the step's gradients, which belong to the other
// direction, are not applied).
#pragma once
#include <cstdint>

#include "gpu/buffer.h"
#include "loss/event_loss.h"

namespace evflow {

class DirectionCheck {
 public:
  DirectionCheck(gpu::Context& ctx, EventLoss& events, uint32_t until_step, double margin);
  bool active(uint32_t step) const { return step <= until_step_; }
  // Asks the event loss's next record for the value of the same frames, pairs and seed in the
  // time-reversed order, written apart from the term's value slot (EventLoss::score_reversed_next:
  // with per-pixel pairs, from the forward order's own pass over the counts).
  void score_reversed_next();
  // After the event loss's record of the forward order: a copy of its value beside the reversed
  // one, so that the two come back in one download.
  void keep_forward(gpu::Commands& cmd);
  // After the submit of the two records: reads the two values (one download) and compares.
  bool prefers_reversed() const;
  // The rule: the reversed order's value is below (1 - margin) times the forward order's.
  static bool prefers(double forward, double reversed, double margin);

 private:
  EventLoss& events_;
  uint32_t until_step_;
  double margin_;
  gpu::Buffer scores_;  // two floats: the forward and the reversed order's values
};

}  // namespace evflow
