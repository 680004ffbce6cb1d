// EDI: Event-based Double Integral deblurring (Pan et al., CVPR 2019; the paper's Eq. 3).
//
// Model. A blurry linear image is the mean of the latent sharp images over the exposure
// T = [t0, t1]:  B = (1/T) ∫_T I(t) dt. Per pixel, events relate the latent image at two times:
//     log I(t) - log I(f) = E(f, t),
//     E(f, t) =  Σ_{f < s_k <= t} c(p_k) p_k   for t >= f,
//     E(f, t) = -Σ_{t < s_k <= f} c(p_k) p_k   for t <  f,
// with c(+1) = Θ+ and c(-1) = Θ- (thresholds, possibly per pixel). Hence
//     B = I(f) · (1/T) ∫_T exp(E(f, t)) dt   and   I(f) = B / D(f),
//     D(f) = (1/T) ∫_T exp(E(f, t)) dt       (the event double integral).
//
// Exact evaluation. Let one pixel's events in T be s_1 <= ... <= s_m, s_0 = t0, s_{m+1} = t1, and
// C_j = Σ_{k<=j} c(p_k) p_k the cumulative level after j events (C_0 = 0). E(f, t) = C(t) - C(f)
// is piecewise constant, C(t) = C_j on [s_j, s_{j+1}), so
//     D(f) = exp(-C(f)) · (1/T) Σ_{j=0..m} exp(C_j) (s_{j+1} - s_j).
// The sum S = Σ_j exp(C_j - C_max) (s_{j+1} - s_j) does not depend on f: it is computed once per
// pixel (C_max = max_j C_j keeps the exponentials <= 1), then
//     I(f) = B · T · exp(C(f) - C_max) / S,
// where C(f) is the level after the pixel's last event with s_k <= f. Building the per-pixel event
// lists and S is O(events + pixels); each frame then costs O(pixels · log(events per pixel)).
//
// Conventions: the events used are those of the stream with t0 <= t < t1 (EventStream::window);
// f must lie in [t0, t1]; the output is linear and unclamped (it can exceed 1, or amplify noise
// where B is dark); a colour B (H*W*3 interleaved) is divided channel-wise by the same per-pixel
// D(f) (with luminance events this is the standard colour EDI; CFA events would need demosaicing).
#pragma once

#include <cstdint>
#include <vector>

#include "events/event_stream.h"

namespace evflow::events {

struct EdiThresholds {
  double pos = 0.2;  // Θ+ (log units per positive event)
  double neg = 0.2;  // Θ- (log units per negative event, > 0)
  // Optional per-pixel thresholds (H*W, row-major); when non-empty they replace pos / neg.
  std::vector<double> pos_map, neg_map;
};

class EdiIntegrator {
 public:
  // Gathers the events of `ev` in [t0, t1) per pixel and precomputes the double-integral sums.
  // Throws std::runtime_error if t1 <= t0, a threshold is not positive or a map has the wrong size.
  EdiIntegrator(const EventStream& ev, double t0, double t1, const EdiThresholds& th = {});

  // D(f) per pixel (H*W): (1/T) ∫_T exp(E(f, t)) dt.
  std::vector<double> double_integral(double f) const;
  // Latent sharp image I(f) = B / D(f); blurry is H*W*channels (1 or 3, interleaved), linear.
  std::vector<float> frame_at(const float* blurry, uint32_t channels, double f) const;
  std::vector<float> frame_mid(const float* blurry, uint32_t channels) const {
    return frame_at(blurry, channels, 0.5 * (t0_ + t1_));
  }

  // Net signed log change Σ c p of each pixel's events in [t0, f] (C(f) above).
  std::vector<double> level_at(double f) const;

  uint32_t width() const { return w_; }
  uint32_t height() const { return h_; }
  double t0() const { return t0_; }
  double t1() const { return t1_; }
  size_t event_count() const { return time_.size(); }

 private:
  double level_of(size_t pixel, double f) const;
  void check_time(double f) const;

  uint32_t w_, h_;
  double t0_, t1_;
  std::vector<uint32_t> offset_;  // per-pixel ranges into time_ / level_ (size H*W + 1)
  std::vector<double> time_;      // event times, grouped by pixel, increasing within a pixel
  std::vector<double> level_;     // C_j after each event
  std::vector<double> cmax_;      // per pixel max_j C_j (>= 0)
  std::vector<double> sum_;       // per pixel S = Σ exp(C_j - C_max) (s_{j+1} - s_j)
};

// One-shot helper: the sharp latent image at mid-exposure.
std::vector<float> edi_deblur(const float* blurry, uint32_t channels, const EventStream& ev, double t0, double t1,
                              const EdiThresholds& th = {});

}  // namespace evflow::events
