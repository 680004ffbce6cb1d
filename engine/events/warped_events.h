// Events warped along optical flow to the end of their interval (paper Eq. 6): the measured side
// of the warped-event loss (loss/warped_event_loss.h). Events of one edge, spread along its path
// during the interval, stack where the edge is at the interval's end.
#pragma once
#include <vector>

#include "events/event_stream.h"

namespace evflow {

// The events of `stream` with ta <= t < tb moved to tb along the displacement field `d` (H * W * 2:
// u, v per pixel, in pixels over [ta, tb]):
//
//   x' = x + (tb - t) / (tb - ta) * d(x),
//
// each voting +theta_pos (positive event) or -theta_neg (negative) into the four pixels around
// x' (bilinear; votes off the sensor are lost). Events on a pixel whose displacement is not
// finite are dropped. Returns H * W values, accumulated in double precision.
std::vector<float> warp_events_to_end(const EventStream& stream, double ta, double tb, const std::vector<float>& d,
                                      double theta_pos, double theta_neg);

}  // namespace evflow
