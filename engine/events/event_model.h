// DVS event model: the event half of the simulator (ESIM / v2e style), on the CPU.
//
// The simulator renders linear-intensity sub-frames along the camera trajectory and feeds them
// here one at a time (EventSimulator::add_frame); events are appended to an internal, globally
// time-sorted EventStream.
//
// Model (per pixel), see shared/design/REFERENCE.md §3:
//  * Log intensity L = log(eps + I), I linear in [0, 1] (negative inputs are clamped to 0,
//    non-finite inputs throw). eps = 1e-3 by default.
//  * Each pixel keeps a reference level L_ref (initialised to the first frame's L). Between two
//    consecutive frames (t0, L0) and (t1, L1) the log intensity is interpolated linearly; each time
//    L - L_ref reaches +Θ+ (resp. -Θ-) an event p = +1 (resp. -1) is emitted at the interpolated
//    crossing time and L_ref moves by +Θ+ (resp. -Θ-):
//        t_k = t0 + (t1 - t0) (L_ref + k p Θ - L0) / (L1 - L0),  k = 1, 2, ...
//    A crossing that lands within 1e-9 (log units) of the threshold at the end of an interval is
//    emitted (at t1), so a ramp ending exactly on a threshold multiple fires its last event.
//  * Thresholds are fixed per pixel at construction: Θ+ ~ N(theta_pos, theta_sigma),
//    Θ- ~ N(theta_neg, theta_sigma), each clamped to >= theta_min.
//  * Refractory period: a crossing less than `refractory_s` after the pixel's last EMITTED event
//    is dropped, but the reference level still advances by the threshold (as a real pixel resets
//    anyway; this keeps L - L_ref bounded so the signal is not shifted after the dead time).
//    Dropped crossings do not restart the refractory clock.
//  * Leak noise (leak_rate_hz > 0): the reference level drifts down at leak_rate_hz * theta_pos
//    (nominal) log units per second, so a static pixel fires positive events at about
//    leak_rate_hz (exactly, when its Θ+ equals the nominal value). Each pixel's initial reference
//    gets a uniform random phase in [0, Θ+) below L so leak events are not synchronised. The drift
//    is linear in time, so crossings are still solved exactly per interval.
//  * Shot noise (shot_rate_hz > 0, per pixel, both polarities together): a Poisson process over the
//    whole sensor (rate shot_rate_hz * W * H), each arrival at a uniformly random pixel with a
//    random polarity. Shot events are additive: they do not touch the pixel's reference level or
//    refractory clock (background-activity model).
//  * Timestamp jitter (jitter_s > 0): every event's time gets N(0, jitter_s) noise, clamped to
//    ±6 jitter_s, and the stream is re-sorted. Events are held back until no later frame can
//    produce an earlier one: events() holds those older than (last frame time - 6 jitter_s);
//    call finish() (take_events() does) after the last frame to flush the rest.
//  * Colour: ColorMode::Luma (default) uses the frame as given (add_frame) or the linear Rec.709
//    luminance 0.2126 R + 0.7152 G + 0.0722 B (add_frame_rgb). ColorMode::RGGB puts a Bayer colour
//    filter in front of the sensor: pixel (x, y) sees R if x, y both even, B if both odd, G
//    otherwise (add_frame_rgb picks that channel; add_frame treats the frame as grey, R = G = B).
//  * Determinism: std::mt19937_64 with hand-written uniform / Box-Muller normal / exponential
//    sampling. Independent sub-streams (thresholds, leak phases, shot noise, jitter) are derived
//    from `seed` with splitmix64, so e.g. enabling jitter does not change the noise events.
//    Within one interval events are ordered by (t, y, x, p).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <nlohmann/json.hpp>

#include "events/event_stream.h"

namespace evflow::events {

enum class ColorMode { Luma, RGGB };

struct EventModelParams {
  double theta_pos = 0.2;      // mean positive (ON) contrast threshold, log units
  double theta_neg = 0.2;      // mean negative (OFF) contrast threshold, log units (> 0)
  double theta_sigma = 0.03;   // per-pixel threshold standard deviation (fixed pattern)
  double theta_min = 0.01;     // per-pixel thresholds are clamped to >= this
  double eps = 1e-3;           // L = log(eps + I)
  double refractory_s = 5e-4;  // dead time after an emitted event (0 = none)
  double shot_rate_hz = 0.0;   // shot noise events per pixel per second (both polarities)
  double leak_rate_hz = 0.0;   // leak (positive) events per pixel per second on a static scene
  double jitter_s = 0.0;       // timestamp jitter standard deviation
  ColorMode color = ColorMode::Luma;
  uint64_t seed = 0;  // recorded for the manifest; EventSimulator's seed argument wins

  // v2e-like defaults (the struct's defaults).
  static EventModelParams defaults() { return {}; }
  // v2e "noisy" preset: sigma 0.05, 5 Hz shot noise, 0.1 Hz leak.
  static EventModelParams noisy();
  // Exact thresholds, no refractory period, no noise (for tests and EDI sanity checks).
  static EventModelParams ideal();

  nlohmann::json to_json() const;
  // Missing keys keep their defaults; unknown keys or invalid values throw std::runtime_error.
  static EventModelParams from_json(const nlohmann::json& j);
  // Throws std::runtime_error on invalid values (non-positive means, negative sigmas/rates...).
  void validate() const;
};

// nlohmann ADL hooks: `nlohmann::json j = params;` / `j.get<EventModelParams>()`.
void to_json(nlohmann::json& j, const EventModelParams& p);
void from_json(const nlohmann::json& j, EventModelParams& p);

class EventSimulator {
 public:
  EventSimulator(uint32_t width, uint32_t height, const EventModelParams& params, uint64_t seed);

  // Append the frame taken at time t (strictly increasing across calls). The first frame only
  // initialises the reference levels. linear_luma: H*W linear intensities, row-major.
  void add_frame(const float* linear_luma, double t);
  void add_frame(const double* linear_luma, double t);
  // rgb: H*W*3 interleaved linear RGB (luminance in Luma mode, one Bayer channel in RGGB mode).
  void add_frame_rgb(const float* rgb, double t);
  // Log-domain frame L = log(eps + I) given directly (H*W), bypassing the conversion.
  void add_log_frame(const double* log_luma, double t);

  // Flush the events held back for jitter re-sorting (no-op without jitter). Call after the last
  // frame if jitter_s > 0; further frames may still be added afterwards only if their events are
  // not earlier than the flushed ones (they are not re-sorted against them).
  void finish();

  const EventStream& events() const { return out_; }
  // finish(), then move the events out (the internal stream is left empty, state is kept).
  EventStream take_events();

  const EventModelParams& params() const { return params_; }  // seed field = the seed in use
  uint32_t width() const { return w_; }
  uint32_t height() const { return h_; }
  size_t frames_added() const { return frames_; }
  double last_time() const { return t_prev_; }
  // Per-pixel thresholds (H*W, row-major), fixed at construction.
  const std::vector<double>& theta_pos_map() const { return th_pos_; }
  const std::vector<double>& theta_neg_map() const { return th_neg_; }
  // Current per-pixel reference levels (log units).
  const std::vector<double>& reference_levels() const { return ref_; }
  // Number of signal crossings dropped by the refractory period so far.
  uint64_t refractory_dropped() const { return dropped_; }

 private:
  struct Ev {
    double t;
    uint16_t x, y;
    int8_t p;
  };
  void step(double t);  // consumes logbuf_
  void flush_until(double t_limit, bool all);

  uint32_t w_, h_;
  EventModelParams params_;
  std::mt19937_64 rng_leak_, rng_shot_, rng_jitter_;
  std::vector<double> th_pos_, th_neg_;
  std::vector<double> ref_, prev_L_, t_last_;
  std::vector<double> logbuf_;
  std::vector<Ev> scratch_, pending_;
  double t_prev_ = 0.0;
  double next_shot_ = 0.0;
  size_t frames_ = 0;
  uint64_t dropped_ = 0;
  EventStream out_;
};

// Portable samplers on std::mt19937_64 (exposed for tests and other simulator parts).
double uniform01(std::mt19937_64& g);                 // [0, 1), 53 random bits
double uniform01_open(std::mt19937_64& g);            // (0, 1]
double normal01(std::mt19937_64& g);                  // Box-Muller, one value per call (2 draws)
double exponential(std::mt19937_64& g, double rate);  // mean 1/rate
uint64_t poisson(std::mt19937_64& g, double mean);    // exact: Knuth below mean 30, Hoermann's PTRS above
uint64_t splitmix64(uint64_t& state);

}  // namespace evflow::events
