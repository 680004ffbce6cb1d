#include "prior/training_samples.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "camera/trajectory.h"
#include "events/edi.h"
#include "io/image.h"
#include "prior/event_inputs.h"
#include "prior/training_rooms.h"
#include "sim/simulator.h"

namespace evflow::prior {

namespace {

// A linear image as an 8-bit sRGB PNG holds it, back in linear.
std::vector<float> as_8bit(const std::vector<float>& linear) {
  std::vector<float> out(linear.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const float e = std::round(std::clamp(io::linear_to_srgb(std::clamp(linear[i], 0.f, 1.f)), 0.f, 1.f) * 255.f);
    out[i] = io::srgb_to_linear(e / 255.f);
  }
  return out;
}

// Appends a - b (H*W*3 interleaved each) as three planes.
void append_difference_planes(const std::vector<float>& a, const std::vector<float>& b, std::vector<float>& out) {
  const size_t hw = a.size() / 3;
  const size_t first = out.size();
  out.resize(first + 3 * hw);
  for (size_t p = 0; p < hw; ++p)
    for (size_t c = 0; c < 3; ++c) out[first + c * hw + p] = a[p * 3 + c] - b[p * 3 + c];
}

sim::SimParams room_params(uint64_t seed, const SampleOptions& o) {
  sim::SimParams p;
  p.width = o.width, p.height = o.height;
  p.train_views = o.views_per_room;
  p.novel_views = 0;
  p.seed = seed;
  std::mt19937_64 g(seed * 31 + 7);
  p.blur_px = std::uniform_real_distribution<double>(o.blur_min_px, o.blur_max_px)(g);
  p.shake = seed % 2 ? "smooth" : "jerk";
  return p;
}

PriorSample simulate_view(sim::Simulator& sim, const sim::SimParams& p, int v, const std::vector<double>& u,
                          bool with_edi) {
  events::EventSimulator ev(p.width, p.height, p.events, p.seed + v);
  const sim::TrainViewResult r = sim.simulate_view(v, ev);
  const EventStream events = ev.take_events();
  PriorSample s;
  s.width = p.width, s.height = p.height;
  const std::vector<float> blurry = as_8bit(r.blurry);
  s.input = network_input(blurry, event_planes(events, r.t0, r.t1, u), p.width, p.height);
  std::unique_ptr<events::EdiIntegrator> edi;
  std::vector<float> edi_mid;
  if (with_edi) {
    events::EdiThresholds th;
    th.pos = p.events.theta_pos, th.neg = p.events.theta_neg;
    edi = std::make_unique<events::EdiIntegrator>(events, r.t0, r.t1, th);
    edi_mid = edi->frame_at(blurry.data(), 3, r.t0 + 0.5 * (r.t1 - r.t0));
  }
  const size_t mid = u.size() / 2;
  for (size_t i = 0; i < u.size(); ++i) {
    if (i == mid) continue;
    const sim::Frame f = sim.renderer().render(sim.shake_pose(v, u[i], r.shake_scale));
    append_difference_planes(f.rgb, r.sharp_mid.rgb, s.target);
    if (with_edi)
      append_difference_planes(edi->frame_at(blurry.data(), 3, r.t0 + u[i] * (r.t1 - r.t0)), edi_mid, s.edi_residual);
  }
  return s;
}

}  // namespace

std::vector<PriorSample> simulate_samples(gpu::Context& ctx, const std::vector<uint64_t>& room_seeds,
                                          const SampleOptions& o, bool with_edi) {
  const std::vector<double> u = ExposureTrajectory::virtual_times(int(o.frames / 2));
  if (u.size() != o.frames) throw std::invalid_argument("prior samples: the frame count must be odd");
  std::vector<PriorSample> out;
  for (uint64_t seed : room_seeds) {
    const sim::Scene scene = make_training_room(seed);
    const sim::SimParams p = room_params(seed, o);
    sim::Simulator sim(ctx, scene, p);
    for (int v = 0; v < p.train_views; ++v) out.push_back(simulate_view(sim, p, v, u, with_edi));
  }
  return out;
}

Crop crop(const PriorSample& s, uint32_t x, uint32_t y, uint32_t size) {
  if (x + size > s.width || y + size > s.height) throw std::invalid_argument("prior crop: outside the sample");
  const size_t hw = size_t(s.width) * s.height;
  auto planes = [&](const std::vector<float>& v, std::vector<float>& out) {
    const size_t n = v.size() / hw;
    out.resize(n * size * size);
    for (size_t c = 0; c < n; ++c)
      for (uint32_t r = 0; r < size; ++r) {
        const float* src = v.data() + c * hw + size_t(y + r) * s.width + x;
        std::copy(src, src + size, out.begin() + (c * size + r) * size);
      }
  };
  Crop c;
  planes(s.input, c.input);
  planes(s.target, c.target);
  return c;
}

}  // namespace evflow::prior
