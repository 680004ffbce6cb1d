// The residual network's input planes (prior/residual_net.h): the blurry image and, per
// non-middle virtual frame i, the accumulation of the exposure's events between the middle frame
// t_N and t_i, one plane per polarity:
//   E+(i) = s * sum over positive events in the window,  E-(i) = -s * (number of negative events),
// over the window (t_N, t_i] for i > N, and negated over (t_i, t_N] for i < N (as EDI's E(f, t)
// with f = t_N, events/edi.h), s = kEventScale. The two polarities stay apart because their
// thresholds differ per pixel and a pixel's noise (an event and its opposite) cancels in a signed
// sum but not per polarity.
#pragma once
#include <cstdint>
#include <vector>

#include "events/event_stream.h"

namespace evflow::prior {

// Scale of one event in the input planes (the simulator's nominal contrast threshold, so a plane
// is roughly a log-intensity change).
inline constexpr float kEventScale = 0.2f;

// 2 * (F - 1) planes of H x W (planar, frame order, positive then negative), for the F = u.size()
// virtual frames at times t0 + u[i] (t1 - t0), u increasing with an odd count; the middle one is t_N.
std::vector<float> event_planes(const EventStream& events, double t0, double t1, const std::vector<double>& u);

// The network's whole input: the blurry image (H*W*3 interleaved linear RGB) as three planes, then
// the event planes.
std::vector<float> network_input(const std::vector<float>& blurry_hwc, const std::vector<float>& event_planes,
                                 uint32_t width, uint32_t height);

}  // namespace evflow::prior
