// The LDI's initialisation to EDI (engine/ldi/ldi_prefit.h): on a small simulated scene (a
// texture moving diagonally, the default sensor model with its threshold mismatch), the network
// regressed to EDI's constant-threshold double integral on random crops gives sharp frames as
// close to the simulator's ground truth as EDI's own, within 0.5 dB, at 7 times of the exposure.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "events/edi.h"
#include "events/event_model.h"
#include "events/gpu_events.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "ldi/ldi_model.h"
#include "ldi/ldi_prefit.h"

using namespace evflow;

namespace {

struct MovingTexture {
  uint32_t w = 40, h = 32;
  double T = 0.04, vx = 7.0 / 0.04, vy = 4.0 / 0.04;  // 7 x 4 px over the exposure
  std::vector<float> frame(double t) const {
    std::vector<float> img(size_t(w) * h);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const double u = x + 0.5 - vx * t, v = y + 0.5 - vy * t;
        const double edges = std::tanh(2.5 * std::sin(0.45 * u + 0.2 * v)) * std::cos(0.3 * v);
        img[size_t(y) * w + x] = float(0.45 + 0.3 * edges + 0.1 * std::sin(0.9 * u - 0.7 * v));
      }
    return img;
  }
};

double psnr(const std::vector<float>& a, const std::vector<float>& b) {
  double mse = 0;
  for (size_t i = 0; i < b.size(); ++i) mse += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return 10.0 * std::log10(double(b.size()) / mse);
}

}  // namespace

TEST_CASE("LDI pre-fit: frames within 0.5 dB of EDI's on a simulated scene", "[ldi][gpu]") {
  const auto start = std::chrono::steady_clock::now();
  auto& ctx = test::gpu_context();
  const MovingTexture sc;
  const auto params = events::EventModelParams::defaults();
  events::EventSimulator sim(sc.w, sc.h, params, 5);
  std::vector<double> acc(size_t(sc.w) * sc.h, 0.0);
  const int steps = 300;
  for (int k = 0; k <= steps; ++k) {
    const auto f = sc.frame(sc.T * k / steps);
    sim.add_frame(f.data(), sc.T * k / steps);
    for (size_t i = 0; i < f.size(); ++i) acc[i] += (k == 0 || k == steps ? 0.5 : 1.0) * f[i] / steps;
  }
  const EventStream stream = sim.take_events();
  const std::vector<float> blurry(acc.begin(), acc.end());
  GpuEvents events(ctx, stream, {{0.0, sc.T}}, "simulated events");
  const events::EdiThresholds th{params.theta_pos, params.theta_neg, {}, {}};

  const std::vector<uint32_t> widths{32, 16, 16, 1};  // the fast preset's
  ldi::LdiModel fit(ctx, events, widths, 24, 24, 2);
  fit.init(1);
  ldi::PrefitOptions o;
  o.steps = 250, o.frames = 2, o.lr = 3e-3f, o.seed = 2, o.thresholds = th;
  const ldi::PrefitReport rep = ldi::prefit_to_edi(ctx, fit, stream, events, o);

  // The whole image with the fitted weights, at 7 frame times.
  std::vector<double> times;
  for (int i = 0; i <= 6; ++i) times.push_back(sc.T * i / 6);
  ldi::LdiModel full(ctx, events, widths, sc.w, sc.h, 7);
  nn::SafetensorsFile weights;
  fit.save(weights);
  full.load(weights, "pre-fit weights");
  gpu::Buffer b3(ctx, blurry.size() * 12, "blurry");
  std::vector<float> planes(blurry);
  planes.insert(planes.end(), blurry.begin(), blurry.end());
  planes.insert(planes.end(), blurry.begin(), blurry.end());
  b3.write(planes);
  gpu::Commands cmd(ctx);
  full.forward(cmd, 0, times, {0, 0, sc.w, sc.h}, b3);
  cmd.submit();
  const events::EdiIntegrator edi(stream, 0.0, sc.T, th);
  double p_ldi = 0, p_edi = 0, p_blur = 0;
  for (size_t i = 0; i < times.size(); ++i) {
    const auto sharp = sc.frame(times[i]);
    const std::vector<float> mine = full.frame(uint32_t(i)).read<float>(sharp.size());  // channel 0
    p_ldi += psnr(mine, sharp) / 7, p_edi += psnr(edi.frame_at(blurry.data(), 1, times[i]), sharp) / 7;
    p_blur += psnr(blurry, sharp) / 7;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "[LDI pre-fit] %ux%u, %zu events, %u steps on 24x24 crops: log-E regression %.4f -> %.5f; mean PSNR over 7 "
      "frames: blurry %.2f dB, EDI %.2f dB, LDI %.2f dB (%.1f s)\n",
      sc.w, sc.h, stream.size(), rep.steps, rep.first_loss, rep.last_loss, p_blur, p_edi, p_ldi, seconds);
  CHECK(rep.last_loss < 0.1 * rep.first_loss);
  CHECK(p_edi > p_blur + 3.0);
  CHECK(std::abs(p_ldi - p_edi) <= 0.5);
  test::require_no_validation_messages();
}
