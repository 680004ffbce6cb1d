#include "events/edi.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace evflow::events {

EdiIntegrator::EdiIntegrator(const EventStream& ev, double t0, double t1, const EdiThresholds& th)
    : w_(ev.width), h_(ev.height), t0_(t0), t1_(t1) {
  if (!(std::isfinite(t0) && std::isfinite(t1) && t1 > t0))
    throw std::runtime_error("EDI: exposure window [" + std::to_string(t0) + ", " + std::to_string(t1) + "] is empty");
  if (w_ == 0 || h_ == 0) throw std::runtime_error("EDI: event stream has no sensor size");
  const size_t n = size_t(w_) * h_;
  if (!th.pos_map.empty() && th.pos_map.size() != n)
    throw std::runtime_error("EDI: pos_map has " + std::to_string(th.pos_map.size()) + " values, expected " +
                             std::to_string(n));
  if (!th.neg_map.empty() && th.neg_map.size() != n)
    throw std::runtime_error("EDI: neg_map has " + std::to_string(th.neg_map.size()) + " values, expected " +
                             std::to_string(n));
  if (th.pos_map.empty() && !(th.pos > 0)) throw std::runtime_error("EDI: positive threshold must be > 0");
  if (th.neg_map.empty() && !(th.neg > 0)) throw std::runtime_error("EDI: negative threshold must be > 0");

  const auto [a, b] = ev.window(t0, t1);
  // Counting sort by pixel (stable, so each pixel's events stay in time order).
  offset_.assign(n + 1, 0);
  for (size_t k = a; k < b; ++k) offset_[size_t(ev.y[k]) * w_ + ev.x[k] + 1]++;
  for (size_t i = 0; i < n; ++i) offset_[i + 1] += offset_[i];
  time_.resize(b - a);
  std::vector<int8_t> pol(b - a);
  {
    std::vector<uint32_t> cursor(offset_.begin(), offset_.end() - 1);
    for (size_t k = a; k < b; ++k) {
      const size_t i = size_t(ev.y[k]) * w_ + ev.x[k];
      const uint32_t slot = cursor[i]++;
      time_[slot] = ev.t[k];
      pol[slot] = ev.p[k];
    }
  }
  level_.resize(b - a);
  cmax_.assign(n, 0.0);
  sum_.assign(n, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const double cp = th.pos_map.empty() ? th.pos : th.pos_map[i];
    const double cn = th.neg_map.empty() ? th.neg : th.neg_map[i];
    const uint32_t lo = offset_[i], hi = offset_[i + 1];
    double c = 0.0, cmax = 0.0;
    for (uint32_t k = lo; k < hi; ++k) {
      c += pol[k] > 0 ? cp : -cn;
      level_[k] = c;
      cmax = std::max(cmax, c);
    }
    // S = Σ_j exp(C_j - C_max) (s_{j+1} - s_j), s_0 = t0, s_{m+1} = t1.
    double s = 0.0, prev_t = t0, prev_c = 0.0;
    for (uint32_t k = lo; k < hi; ++k) {
      s += std::exp(prev_c - cmax) * (time_[k] - prev_t);
      prev_t = time_[k];
      prev_c = level_[k];
    }
    s += std::exp(prev_c - cmax) * (t1 - prev_t);
    cmax_[i] = cmax;
    sum_[i] = s;
  }
}

void EdiIntegrator::check_time(double f) const {
  if (!(f >= t0_ && f <= t1_))
    throw std::runtime_error("EDI: reference time " + std::to_string(f) + " is outside the exposure [" +
                             std::to_string(t0_) + ", " + std::to_string(t1_) + "]");
}

double EdiIntegrator::level_of(size_t i, double f) const {
  const double* first = time_.data() + offset_[i];
  const double* last = time_.data() + offset_[i + 1];
  const double* it = std::upper_bound(first, last, f);  // events with s_k <= f come before it
  return it == first ? 0.0 : level_[size_t(it - time_.data()) - 1];
}

std::vector<double> EdiIntegrator::level_at(double f) const {
  check_time(f);
  const size_t n = size_t(w_) * h_;
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = level_of(i, f);
  return out;
}

std::vector<double> EdiIntegrator::double_integral(double f) const {
  check_time(f);
  const size_t n = size_t(w_) * h_;
  const double T = t1_ - t0_;
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) out[i] = std::exp(cmax_[i] - level_of(i, f)) * sum_[i] / T;
  return out;
}

std::vector<float> EdiIntegrator::frame_at(const float* blurry, uint32_t channels, double f) const {
  if (channels != 1 && channels != 3) throw std::runtime_error("EDI: blurry image must have 1 or 3 channels");
  check_time(f);
  const size_t n = size_t(w_) * h_;
  const double T = t1_ - t0_;
  std::vector<float> out(n * channels);
  for (size_t i = 0; i < n; ++i) {
    // I = B / D = B · T · exp(C(f) - C_max) / S. S >= exp(C_last - C_max)·0 + ... > 0 unless every
    // segment has zero length; guard that degenerate case by returning B.
    const double s = sum_[i];
    const double gain = s > 0 ? T * std::exp(level_of(i, f) - cmax_[i]) / s : 1.0;
    for (uint32_t c = 0; c < channels; ++c) out[i * channels + c] = static_cast<float>(blurry[i * channels + c] * gain);
  }
  return out;
}

std::vector<float> edi_deblur(const float* blurry, uint32_t channels, const EventStream& ev, double t0, double t1,
                              const EdiThresholds& th) {
  return EdiIntegrator(ev, t0, t1, th).frame_mid(blurry, channels);
}

}  // namespace evflow::events
