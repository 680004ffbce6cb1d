#include "events/event_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace evflow::events {

// ---------------------------------------------------------------------------------------------
// Portable sampling
// ---------------------------------------------------------------------------------------------

uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double uniform01(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

double uniform01_open(std::mt19937_64& g) { return (static_cast<double>(g() >> 11) + 1.0) * 0x1.0p-53; }

double normal01(std::mt19937_64& g) {
  const double u1 = uniform01_open(g);
  const double u2 = uniform01(g);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586476925 * u2);
}

double exponential(std::mt19937_64& g, double rate) { return -std::log(uniform01_open(g)) / rate; }

uint64_t poisson(std::mt19937_64& g, double mean) {
  if (!(mean > 0.0)) return 0;
  if (mean < 30.0) {  // Knuth: multiply uniforms until the product drops below exp(-mean)
    const double limit = std::exp(-mean);
    double prod = uniform01_open(g);
    uint64_t k = 0;
    while (prod > limit) {
      ++k;
      prod *= uniform01_open(g);
    }
    return k;
  }
  // Transformed rejection with squeeze (W. Hoermann, "The transformed rejection method for
  // generating Poisson random variables", Insurance: Mathematics and Economics 12, 1993).
  const double slam = std::sqrt(mean), loglam = std::log(mean);
  const double b = 0.931 + 2.53 * slam;
  const double a = -0.059 + 0.02483 * b;
  const double inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
  const double v_r = 0.9277 - 3.6224 / (b - 2.0);
  for (;;) {
    const double u = uniform01(g) - 0.5;
    const double v = uniform01(g);
    const double us = 0.5 - std::fabs(u);
    if (us <= 0.0) continue;
    const double k = std::floor((2.0 * a / us + b) * u + mean + 0.43);
    if (us >= 0.07 && v <= v_r) return static_cast<uint64_t>(k);
    if (k < 0.0 || (us < 0.013 && v > us)) continue;
    if (std::log(v) + std::log(inv_alpha) - std::log(a / (us * us) + b) <= -mean + k * loglam - std::lgamma(k + 1.0))
      return static_cast<uint64_t>(k);
  }
}

// ---------------------------------------------------------------------------------------------
// Parameters
// ---------------------------------------------------------------------------------------------

EventModelParams EventModelParams::noisy() {
  EventModelParams p;
  p.theta_sigma = 0.05;
  p.shot_rate_hz = 5.0;
  p.leak_rate_hz = 0.1;
  return p;
}

EventModelParams EventModelParams::ideal() {
  EventModelParams p;
  p.theta_sigma = 0.0;
  p.refractory_s = 0.0;
  p.shot_rate_hz = 0.0;
  p.leak_rate_hz = 0.0;
  p.jitter_s = 0.0;
  return p;
}

void EventModelParams::validate() const {
  auto fail = [](const std::string& what) { throw std::runtime_error("EventModelParams: " + what); };
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(theta_pos) || theta_pos <= 0) fail("theta_pos must be > 0");
  if (!finite(theta_neg) || theta_neg <= 0) fail("theta_neg must be > 0");
  if (!finite(theta_sigma) || theta_sigma < 0) fail("theta_sigma must be >= 0");
  if (!finite(theta_min) || theta_min <= 0) fail("theta_min must be > 0");
  if (!finite(eps) || eps <= 0) fail("eps must be > 0");
  if (!finite(refractory_s) || refractory_s < 0) fail("refractory_s must be >= 0");
  if (!finite(shot_rate_hz) || shot_rate_hz < 0) fail("shot_rate_hz must be >= 0");
  if (!finite(leak_rate_hz) || leak_rate_hz < 0) fail("leak_rate_hz must be >= 0");
  if (!finite(jitter_s) || jitter_s < 0) fail("jitter_s must be >= 0");
}

nlohmann::json EventModelParams::to_json() const {
  nlohmann::json j;
  j["theta_pos"] = theta_pos;
  j["theta_neg"] = theta_neg;
  j["theta_sigma"] = theta_sigma;
  j["theta_min"] = theta_min;
  j["eps"] = eps;
  j["refractory_s"] = refractory_s;
  j["shot_rate_hz"] = shot_rate_hz;
  j["leak_rate_hz"] = leak_rate_hz;
  j["jitter_s"] = jitter_s;
  j["color"] = color == ColorMode::RGGB ? "rggb" : "luma";
  j["seed"] = seed;
  return j;
}

EventModelParams EventModelParams::from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::runtime_error("EventModelParams: expected a JSON object");
  EventModelParams p;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const nlohmann::json& v = it.value();
    auto num = [&]() {
      if (!v.is_number()) throw std::runtime_error("EventModelParams: '" + k + "' must be a number");
      return v.get<double>();
    };
    if (k == "theta_pos")
      p.theta_pos = num();
    else if (k == "theta_neg")
      p.theta_neg = num();
    else if (k == "theta_sigma")
      p.theta_sigma = num();
    else if (k == "theta_min")
      p.theta_min = num();
    else if (k == "eps")
      p.eps = num();
    else if (k == "refractory_s")
      p.refractory_s = num();
    else if (k == "shot_rate_hz")
      p.shot_rate_hz = num();
    else if (k == "leak_rate_hz")
      p.leak_rate_hz = num();
    else if (k == "jitter_s")
      p.jitter_s = num();
    else if (k == "color") {
      const std::string c = v.is_string() ? v.get<std::string>() : std::string();
      if (c == "luma")
        p.color = ColorMode::Luma;
      else if (c == "rggb")
        p.color = ColorMode::RGGB;
      else
        throw std::runtime_error("EventModelParams: 'color' must be \"luma\" or \"rggb\"");
    } else if (k == "seed") {
      if (!v.is_number_integer() || (v.is_number_integer() && !v.is_number_unsigned() && v.get<int64_t>() < 0))
        throw std::runtime_error("EventModelParams: 'seed' must be a non-negative integer");
      p.seed = v.get<uint64_t>();
    } else {
      throw std::runtime_error("EventModelParams: unknown key '" + k + "'");
    }
  }
  p.validate();
  return p;
}

void to_json(nlohmann::json& j, const EventModelParams& p) { j = p.to_json(); }
void from_json(const nlohmann::json& j, EventModelParams& p) { p = EventModelParams::from_json(j); }

// ---------------------------------------------------------------------------------------------
// Simulator
// ---------------------------------------------------------------------------------------------

namespace {
constexpr double kCrossTol = 1e-9;  // log units: crossings this close to a threshold are emitted
constexpr double kJitterClamp = 6.0;
}  // namespace

EventSimulator::EventSimulator(uint32_t width, uint32_t height, const EventModelParams& params, uint64_t seed)
    : w_(width), h_(height), params_(params) {
  if (width == 0 || height == 0 || width > 65536 || height > 65536)
    throw std::runtime_error("EventSimulator: sensor size " + std::to_string(width) + "x" + std::to_string(height) +
                             " is empty or exceeds 16-bit coordinates");
  params_.validate();
  params_.seed = seed;
  uint64_t state = seed;
  std::mt19937_64 rng_th(splitmix64(state));
  rng_leak_.seed(splitmix64(state));
  rng_shot_.seed(splitmix64(state));
  rng_jitter_.seed(splitmix64(state));

  const size_t n = size_t(w_) * h_;
  th_pos_.assign(n, params_.theta_pos);
  th_neg_.assign(n, params_.theta_neg);
  if (params_.theta_sigma > 0) {
    for (size_t i = 0; i < n; ++i) {
      th_pos_[i] = std::max(params_.theta_min, params_.theta_pos + params_.theta_sigma * normal01(rng_th));
      th_neg_[i] = std::max(params_.theta_min, params_.theta_neg + params_.theta_sigma * normal01(rng_th));
    }
  } else {
    for (size_t i = 0; i < n; ++i) {
      th_pos_[i] = std::max(params_.theta_min, th_pos_[i]);
      th_neg_[i] = std::max(params_.theta_min, th_neg_[i]);
    }
  }
  ref_.assign(n, 0.0);
  prev_L_.assign(n, 0.0);
  t_last_.assign(n, -std::numeric_limits<double>::infinity());
  logbuf_.assign(n, 0.0);
  out_.width = w_;
  out_.height = h_;
}

static inline double checked(double v, size_t i) {
  if (!std::isfinite(v)) throw std::runtime_error("EventSimulator: non-finite intensity at pixel " + std::to_string(i));
  return v > 0.0 ? v : 0.0;
}

void EventSimulator::add_frame(const float* linear_luma, double t) {
  const size_t n = logbuf_.size();
  for (size_t i = 0; i < n; ++i) logbuf_[i] = std::log(params_.eps + checked(linear_luma[i], i));
  step(t);
}

void EventSimulator::add_frame(const double* linear_luma, double t) {
  const size_t n = logbuf_.size();
  for (size_t i = 0; i < n; ++i) logbuf_[i] = std::log(params_.eps + checked(linear_luma[i], i));
  step(t);
}

void EventSimulator::add_frame_rgb(const float* rgb, double t) {
  if (params_.color == ColorMode::RGGB) {
    for (uint32_t y = 0; y < h_; ++y)
      for (uint32_t x = 0; x < w_; ++x) {
        const size_t i = size_t(y) * w_ + x;
        // R at (even, even), B at (odd, odd), G elsewhere.
        const int c = (y & 1u) == 0 ? ((x & 1u) == 0 ? 0 : 1) : ((x & 1u) == 0 ? 1 : 2);
        logbuf_[i] = std::log(params_.eps + checked(rgb[3 * i + c], i));
      }
  } else {
    const size_t n = logbuf_.size();
    for (size_t i = 0; i < n; ++i) {
      const double r = checked(rgb[3 * i], i), g = checked(rgb[3 * i + 1], i), b = checked(rgb[3 * i + 2], i);
      logbuf_[i] = std::log(params_.eps + 0.2126 * r + 0.7152 * g + 0.0722 * b);
    }
  }
  step(t);
}

void EventSimulator::add_log_frame(const double* log_luma, double t) {
  const size_t n = logbuf_.size();
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(log_luma[i]))
      throw std::runtime_error("EventSimulator: non-finite log intensity at pixel " + std::to_string(i));
    logbuf_[i] = log_luma[i];
  }
  step(t);
}

void EventSimulator::step(double t) {
  if (!std::isfinite(t)) throw std::runtime_error("EventSimulator: non-finite frame time");
  const size_t n = logbuf_.size();
  const double shot_rate = params_.shot_rate_hz * double(n);
  if (frames_ == 0) {
    const bool leak = params_.leak_rate_hz > 0;
    for (size_t i = 0; i < n; ++i) {
      prev_L_[i] = logbuf_[i];
      ref_[i] = leak ? logbuf_[i] - uniform01(rng_leak_) * th_pos_[i] : logbuf_[i];
    }
    t_prev_ = t;
    next_shot_ = shot_rate > 0 ? t + exponential(rng_shot_, shot_rate) : std::numeric_limits<double>::infinity();
    frames_ = 1;
    return;
  }
  if (!(t > t_prev_))
    throw std::runtime_error("EventSimulator: frame times must increase (got " + std::to_string(t) + " after " +
                             std::to_string(t_prev_) + ")");
  const double t0 = t_prev_, dt = t - t0;
  const double drift = params_.leak_rate_hz * params_.theta_pos * dt;  // reference decrease over the interval
  const double refr = params_.refractory_s;
  scratch_.clear();

  for (uint32_t y = 0; y < h_; ++y) {
    for (uint32_t x = 0; x < w_; ++x) {
      const size_t i = size_t(y) * w_ + x;
      const double L0 = prev_L_[i], L1 = logbuf_[i];
      // D(s) = L(s) - L_ref(s) = D0 + dD s for s in [0, 1] (linear interpolation + linear leak).
      double D = L0 - ref_[i];
      const double dD = (L1 - L0) + drift;
      double ref = ref_[i] - drift;
      auto emit = [&](double s, int8_t p) {
        const double te = t0 + dt * std::clamp(s, 0.0, 1.0);
        if (te - t_last_[i] < refr) {
          ++dropped_;
          return;
        }
        t_last_[i] = te;
        scratch_.push_back({te, static_cast<uint16_t>(x), static_cast<uint16_t>(y), p});
      };
      if (dD > 0) {
        const double th = th_pos_[i];
        while (D + dD >= th - kCrossTol) {
          emit((th - D) / dD, int8_t(1));
          D -= th;
          ref += th;
        }
      } else if (dD < 0) {
        const double th = th_neg_[i];
        while (D + dD <= -th + kCrossTol) {
          emit((-th - D) / dD, int8_t(-1));
          D += th;
          ref -= th;
        }
      }
      ref_[i] = ref;
      prev_L_[i] = L1;
    }
  }

  // Shot noise: a Poisson process over the whole sensor, carried across frames.
  if (shot_rate > 0) {
    while (next_shot_ < t) {
      size_t pix = static_cast<size_t>(uniform01(rng_shot_) * double(n));
      if (pix >= n) pix = n - 1;
      const int8_t p = uniform01(rng_shot_) < 0.5 ? int8_t(1) : int8_t(-1);
      scratch_.push_back(
          {std::max(next_shot_, t0), static_cast<uint16_t>(pix % w_), static_cast<uint16_t>(pix / w_), p});
      next_shot_ += exponential(rng_shot_, shot_rate);
    }
  }

  auto less = [](const Ev& a, const Ev& b) {
    if (a.t != b.t) return a.t < b.t;
    if (a.y != b.y) return a.y < b.y;
    if (a.x != b.x) return a.x < b.x;
    return a.p < b.p;
  };
  std::sort(scratch_.begin(), scratch_.end(), less);

  const double J = kJitterClamp * params_.jitter_s;
  if (params_.jitter_s > 0) {
    for (Ev& e : scratch_) e.t += std::clamp(params_.jitter_s * normal01(rng_jitter_), -J, J);
  }
  if (params_.jitter_s > 0 || !pending_.empty()) {
    pending_.insert(pending_.end(), scratch_.begin(), scratch_.end());
    std::sort(pending_.begin(), pending_.end(), less);
    t_prev_ = t;
    frames_++;
    flush_until(t - J, false);
    return;
  }
  out_.reserve(out_.size() + scratch_.size());
  for (const Ev& e : scratch_) out_.push(e.x, e.y, e.t, e.p);
  t_prev_ = t;
  frames_++;
}

void EventSimulator::flush_until(double t_limit, bool all) {
  size_t k = 0;
  while (k < pending_.size() && (all || pending_[k].t <= t_limit)) {
    const Ev& e = pending_[k];
    out_.push(e.x, e.y, e.t, e.p);
    ++k;
  }
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(k));
}

void EventSimulator::finish() { flush_until(0.0, true); }

EventStream EventSimulator::take_events() {
  finish();
  EventStream s = std::move(out_);
  out_ = EventStream{};
  out_.width = w_;
  out_.height = h_;
  return s;
}

}  // namespace evflow::events
