// Test data: a training view's exposure rendered from known splats along a known motion, its
// blurry image (the linear mean of sub + 1 renders over a grey background) and the events of an
// ideal sensor, as the blur-mode training tests need them.
#pragma once
#include <vector>

#include "camera/trajectory.h"
#include "events/event_model.h"
#include "io/dataset.h"
#include "io/image.h"
#include "splat/rasterizer.h"

namespace evflow::test {

// Sets view v's exposure to [t0, t0 + T] and its blurry image; appends its events to data.events.
inline void simulate_exposure(Rasterizer& r, RenderState& state, const GaussianBuffers& gt, io::Dataset& data, size_t v,
                              const ExposureTrajectory& motion, double t0, double T, int sub, uint64_t seed,
                              float grey) {
  const uint32_t W = data.train[v].camera.width, H = data.train[v].camera.height;
  data.train[v].exposure_start = t0, data.train[v].exposure_end = t0 + T;
  events::EventSimulator sim(W, H, events::EventModelParams::ideal(), seed);
  std::vector<float> mean(size_t(W) * H * 3, 0.f), luma(size_t(W) * H);
  for (int s = 0; s <= sub; ++s) {
    RenderSettings rs;
    rs.background = {grey, grey, grey};
    r.forward(gt, motion.camera_at(s / double(sub)), rs, state);
    auto img = state.outputs().rgb.read<float>(mean.size());
    for (float& x : img) x = io::srgb_to_linear(x);
    for (size_t i = 0; i < luma.size(); ++i)
      luma[i] = 0.2126f * img[i] + 0.7152f * img[luma.size() + i] + 0.0722f * img[2 * luma.size() + i];
    sim.add_frame(luma.data(), t0 + T * s / sub);
    for (size_t i = 0; i < mean.size(); ++i) mean[i] += img[i] / (sub + 1);
  }
  data.train[v].blurry = io::image_from_planar_rgb(mean, W, H);
  const EventStream ev = sim.take_events();
  for (size_t i = 0; i < ev.size(); ++i) data.events.push(ev.x[i], ev.y[i], ev.t[i], ev.p[i]);
}

}  // namespace evflow::test
