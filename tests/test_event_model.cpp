#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "events/event_model.h"

using namespace evflow;
using namespace evflow::events;

namespace {

// Feed a 1-pixel log-intensity signal L(t) sampled at the given times.
template <class F>
EventStream run_log_signal(const EventModelParams& p, F L, const std::vector<double>& times, uint64_t seed = 1) {
  EventSimulator sim(1, 1, p, seed);
  for (double t : times) {
    const double l = L(t);
    sim.add_log_frame(&l, t);
  }
  return sim.take_events();
}

std::vector<double> linspace(double a, double b, int n) {  // n intervals, n + 1 samples
  std::vector<double> v(n + 1);
  for (int i = 0; i <= n; ++i) v[i] = a + (b - a) * i / n;
  return v;
}

bool sorted(const EventStream& s) { return std::is_sorted(s.t.begin(), s.t.end()); }

// A smooth texture translating horizontally at `speed` px/s, linear intensity in [0.05, 0.95].
std::vector<float> moving_pattern(uint32_t w, uint32_t h, double t, double speed) {
  std::vector<float> img(size_t(w) * h);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const double u = x + 0.5 - speed * t;
      img[y * w + x] =
          float(0.5 + 0.3 * std::sin(0.6 * u + 0.4 * y) + 0.15 * std::tanh(std::sin(0.17 * u - 0.3 * y) * 4));
    }
  return img;
}

}  // namespace

TEST_CASE("event model: linear log ramp up gives exact crossing times", "[events]") {
  const auto p = EventModelParams::ideal();
  REQUIRE(p.theta_pos == 0.2);
  auto s = run_log_signal(
      p, [](double t) { return -2.0 + t; }, linspace(0.0, 1.0, 10));
  REQUIRE(s.size() == 5);
  for (size_t k = 0; k < 5; ++k) {
    CHECK(s.p[k] == 1);
    CHECK(std::abs(s.t[k] - 0.2 * double(k + 1)) < 1e-9);
    CHECK(s.x[k] == 0);
    CHECK(s.y[k] == 0);
  }
  // The same with a single interval (the crossing formula, not the sampling, gives the times).
  auto s2 = run_log_signal(p, [](double t) { return -2.0 + t; }, {0.0, 1.0});
  REQUIRE(s2.size() == 5);
  for (size_t k = 0; k < 5; ++k) CHECK(std::abs(s2.t[k] - 0.2 * double(k + 1)) < 1e-9);
}

TEST_CASE("event model: float linear-intensity frames go through log(eps + I)", "[events]") {
  const auto p = EventModelParams::ideal();
  EventSimulator sim(1, 1, p, 3);
  for (double t : linspace(0.0, 1.05, 21)) {
    const float I = float(std::exp(-2.0 + t) - p.eps);
    sim.add_frame(&I, t);
  }
  const auto& s = sim.events();
  REQUIRE(s.size() == 5);
  for (size_t k = 0; k < 5; ++k) CHECK(std::abs(s.t[k] - 0.2 * double(k + 1)) < 1e-6);
}

TEST_CASE("event model: decreasing ramp gives negative events", "[events]") {
  const auto p = EventModelParams::ideal();
  auto s = run_log_signal(
      p, [](double t) { return -0.5 - t; }, linspace(0.0, 1.0, 7));
  REQUIRE(s.size() == 5);
  for (size_t k = 0; k < 5; ++k) {
    CHECK(s.p[k] == -1);
    CHECK(std::abs(s.t[k] - 0.2 * double(k + 1)) < 1e-9);
  }
}

TEST_CASE("event model: separate positive and negative thresholds", "[events]") {
  auto p = EventModelParams::ideal();
  p.theta_pos = 0.25;
  p.theta_neg = 0.5;
  // Up by 1.0 over [0, 1], down by 1.0 over [1, 2].
  auto L = [](double t) { return t <= 1.0 ? -3.0 + t : -2.0 - (t - 1.0); };
  auto s = run_log_signal(p, L, linspace(0.0, 2.0, 8));
  REQUIRE(s.size() == 6);
  const double expect_t[] = {0.25, 0.5, 0.75, 1.0, 1.5, 2.0};
  const int expect_p[] = {1, 1, 1, 1, -1, -1};
  for (size_t k = 0; k < 6; ++k) {
    CHECK(std::abs(s.t[k] - expect_t[k]) < 1e-9);
    CHECK(s.p[k] == expect_p[k]);
  }
}

TEST_CASE("event model: refractory period drops events but the reference advances", "[events]") {
  auto p = EventModelParams::ideal();
  p.refractory_s = 0.5e-3;
  // Up by 1.0 within 1 ms: crossings at 0.2, 0.4, 0.6, 0.8, 1.0 ms; hold; then down by 0.2 at 10-11 ms.
  auto L = [](double t) {
    if (t <= 1e-3) return -2.0 + t / 1e-3;
    if (t <= 10e-3) return -1.0;
    return -1.0 - 0.2 * std::min(1.0, (t - 10e-3) / 1e-3);
  };
  std::vector<double> times = linspace(0.0, 1e-3, 5);
  times.push_back(10e-3);
  times.push_back(11e-3);
  times.push_back(20e-3);
  EventSimulator sim(1, 1, p, 1);
  for (double t : times) {
    const double l = L(t);
    sim.add_log_frame(&l, t);
  }
  const auto& s = sim.events();
  // Emitted: 0.2 ms; 0.4 and 0.6 dropped (< 0.5 ms after 0.2); 0.8 emitted; 1.0 dropped.
  REQUIRE(s.size() == 3);
  CHECK(std::abs(s.t[0] - 0.2e-3) < 1e-9);
  CHECK(std::abs(s.t[1] - 0.8e-3) < 1e-9);
  CHECK(sim.refractory_dropped() == 3);
  // The reference followed all five crossings, so the 0.2 drop fires exactly at its end.
  CHECK(s.p[2] == -1);
  CHECK(std::abs(s.t[2] - 11e-3) < 1e-9);
  CHECK(std::abs(sim.reference_levels()[0] - (-1.2)) < 1e-9);
}

TEST_CASE("event model: per-pixel threshold statistics and clamping", "[events]") {
  auto p = EventModelParams::defaults();
  p.theta_pos = 0.2;
  p.theta_neg = 0.3;
  p.theta_sigma = 0.03;
  EventSimulator sim(200, 200, p, 11);
  auto stats = [](const std::vector<double>& v) {
    double m = 0, m2 = 0;
    for (double x : v) m += x;
    m /= double(v.size());
    for (double x : v) m2 += (x - m) * (x - m);
    return std::pair<double, double>(m, std::sqrt(m2 / double(v.size() - 1)));
  };
  auto [mp, sp] = stats(sim.theta_pos_map());
  auto [mn, sn] = stats(sim.theta_neg_map());
  CHECK(std::abs(mp - 0.2) < 0.001);  // standard error 1.5e-4
  CHECK(std::abs(mn - 0.3) < 0.001);
  CHECK(std::abs(sp - 0.03) < 0.001);  // standard error ~1e-4
  CHECK(std::abs(sn - 0.03) < 0.001);

  auto q = p;
  q.theta_pos = 0.1;
  q.theta_sigma = 0.2;
  EventSimulator sim2(100, 100, q, 11);
  const auto& th = sim2.theta_pos_map();
  CHECK(*std::min_element(th.begin(), th.end()) == 0.01);
  const double clamped = double(std::count(th.begin(), th.end(), 0.01)) / double(th.size());
  CHECK(std::abs(clamped - 0.3264) < 0.03);  // P(N(0.1, 0.2) < 0.01) = Phi(-0.45)

  // The per-pixel thresholds are the ones used: a +1.3 ramp gives floor(1.3 / theta_i) events.
  auto r = p;
  r.refractory_s = 0;
  EventSimulator sim3(40, 40, r, 5);
  std::vector<double> L(1600, -2.0);
  sim3.add_log_frame(L.data(), 0.0);
  for (double& l : L) l += 1.3;
  sim3.add_log_frame(L.data(), 1.0);
  std::vector<int> count(1600, 0);
  const auto& s = sim3.events();
  for (size_t k = 0; k < s.size(); ++k) count[s.y[k] * 40 + s.x[k]]++;
  int mismatches = 0;
  for (size_t i = 0; i < 1600; ++i)
    if (count[i] != int(std::floor(1.3 / sim3.theta_pos_map()[i]))) ++mismatches;
  CHECK(mismatches == 0);
}

TEST_CASE("event model: shot noise count matches rate x pixels x duration", "[events]") {
  auto p = EventModelParams::ideal();
  p.shot_rate_hz = 5.0;
  const uint32_t W = 100, H = 100;
  EventSimulator sim(W, H, p, 7);
  std::vector<float> img(W * H, 0.4f);
  for (double t : linspace(0.0, 1.0, 10)) sim.add_frame(img.data(), t);
  const auto& s = sim.events();
  const double expected = 5.0 * W * H * 1.0;
  CHECK(std::abs(double(s.size()) - expected) < 5 * std::sqrt(expected));
  const double pos = double(std::count(s.p.begin(), s.p.end(), int8_t(1)));
  CHECK(std::abs(pos - 0.5 * double(s.size())) < 5 * 0.5 * std::sqrt(double(s.size())));
  const double first_half = double(std::lower_bound(s.t.begin(), s.t.end(), 0.5) - s.t.begin());
  CHECK(std::abs(first_half - 0.5 * double(s.size())) < 5 * 0.5 * std::sqrt(double(s.size())));
  CHECK(sorted(s));
  REQUIRE_NOTHROW(s.validate("shot noise"));
}

TEST_CASE("event model: leak noise fires positive events at the leak rate", "[events]") {
  auto p = EventModelParams::ideal();
  p.leak_rate_hz = 0.1;
  const uint32_t W = 100, H = 100;
  EventSimulator sim(W, H, p, 9);
  std::vector<float> img(W * H, 0.3f);
  for (double t : linspace(0.0, 10.0, 10)) sim.add_frame(img.data(), t);
  const auto& s = sim.events();
  // Random phase in [0, theta) and a drift of exactly theta over 10 s: one event per pixel.
  CHECK(s.size() >= 9990);
  CHECK(s.size() <= W * H);
  CHECK(std::count(s.p.begin(), s.p.end(), int8_t(1)) == long(s.size()));
  CHECK(sorted(s));
}

TEST_CASE("event model: noisy stream with jitter is sorted, valid and deterministic", "[events]") {
  auto p = EventModelParams::noisy();
  p.jitter_s = 1e-4;
  const uint32_t W = 48, H = 32;
  auto simulate = [&](uint64_t seed, bool check_each) {
    EventSimulator sim(W, H, p, seed);
    for (double t : linspace(0.0, 0.05, 100)) {
      auto img = moving_pattern(W, H, t, 200.0);
      sim.add_frame(img.data(), t);
      if (check_each) REQUIRE(sorted(sim.events()));
    }
    return sim.take_events();
  };
  auto a = simulate(42, true);
  REQUIRE(a.size() > 1000);
  REQUIRE_NOTHROW(a.validate("noisy"));
  CHECK(sorted(a));
  CHECK(std::count(a.p.begin(), a.p.end(), int8_t(-1)) > 100);
  auto b = simulate(42, false);
  CHECK(a.t == b.t);
  CHECK(a.x == b.x);
  CHECK(a.y == b.y);
  CHECK(a.p == b.p);
  auto c = simulate(43, false);
  CHECK(c.t != a.t);
}

TEST_CASE("event model: RGGB colour filter array", "[events]") {
  auto p = EventModelParams::ideal();
  p.color = ColorMode::RGGB;
  auto run = [&](int channel, double gain) {
    EventSimulator sim(2, 2, p, 1);
    std::vector<float> rgb(12, 0.2f);
    sim.add_frame_rgb(rgb.data(), 0.0);
    for (int i = 0; i < 4; ++i) rgb[3 * i + channel] = float(0.2 * gain);
    sim.add_frame_rgb(rgb.data(), 1.0);
    std::vector<int> count(4, 0);
    const auto& s = sim.events();
    for (size_t k = 0; k < s.size(); ++k) count[s.y[k] * 2 + s.x[k]]++;
    return count;
  };
  // log(4.0 * 0.2 + eps) - log(0.2 + eps) = 1.385 -> 6 events.
  CHECK(run(0, 4.0) == std::vector<int>{6, 0, 0, 0});  // R at (0, 0)
  CHECK(run(1, 4.0) == std::vector<int>{0, 6, 6, 0});  // G at (1, 0) and (0, 1)
  CHECK(run(2, 4.0) == std::vector<int>{0, 0, 0, 6});  // B at (1, 1)
  // Luminance mode: every pixel sees 0.2126 R + 0.7152 G + 0.0722 B (log ratio 0.493 -> 2 events).
  p.color = ColorMode::Luma;
  CHECK(run(0, 4.0) == std::vector<int>{2, 2, 2, 2});
}

TEST_CASE("event model: parameters round-trip through JSON with the seed", "[events]") {
  auto p = EventModelParams::noisy();
  p.theta_neg = 0.3;
  p.color = ColorMode::RGGB;
  p.jitter_s = 2e-5;
  EventSimulator sim(4, 4, p, 123456789012345ull);
  nlohmann::json j = sim.params();
  CHECK(j["seed"].get<uint64_t>() == 123456789012345ull);
  CHECK(j["color"] == "rggb");
  CHECK(j["shot_rate_hz"] == 5.0);
  auto q = j.get<EventModelParams>();
  CHECK(q.to_json() == j);
  CHECK(q.theta_neg == 0.3);
  CHECK(q.leak_rate_hz == 0.1);
  CHECK(q.theta_sigma == 0.05);
  auto d = EventModelParams::from_json(nlohmann::json::object());
  CHECK(d.theta_pos == 0.2);
  CHECK(d.theta_sigma == 0.03);
  CHECK(d.refractory_s == 0.5e-3);
  CHECK(d.shot_rate_hz == 0.0);
  CHECK_THROWS(EventModelParams::from_json(nlohmann::json{{"theta", 0.2}}));
  CHECK_THROWS(EventModelParams::from_json(nlohmann::json{{"theta_pos", -0.2}}));
  CHECK_THROWS(EventModelParams::from_json(nlohmann::json{{"color", "rgb"}}));
}

TEST_CASE("event model: input checks", "[events]") {
  auto p = EventModelParams::ideal();
  EventSimulator sim(2, 1, p, 1);
  float img[2] = {0.5f, 0.5f};
  sim.add_frame(img, 1.0);
  CHECK_THROWS(sim.add_frame(img, 1.0));  // time must increase
  float bad[2] = {0.5f, NAN};
  CHECK_THROWS(sim.add_frame(bad, 2.0));
  CHECK_THROWS(EventSimulator(0, 4, p, 1));
}

TEST_CASE("event model: portable samplers", "[events]") {
  std::mt19937_64 g(5);
  const int n = 20000;
  for (double mean : {3.0, 100.0}) {
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
      const double k = double(poisson(g, mean));
      s += k;
      s2 += k * k;
    }
    const double m = s / n, var = s2 / n - m * m;
    CHECK(std::abs(m - mean) < 5 * std::sqrt(mean / n));
    CHECK(std::abs(var / mean - 1.0) < 0.06);
  }
  double s = 0, s2 = 0, e = 0;
  for (int i = 0; i < n; ++i) {
    const double z = normal01(g);
    s += z;
    s2 += z * z;
    e += exponential(g, 4.0);
  }
  CHECK(std::abs(s / n) < 0.04);
  CHECK(std::abs(s2 / n - 1.0) < 0.05);
  CHECK(std::abs(e / n - 0.25) < 0.01);
}
