#include "ldi/ldi_prefit.h"

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>

namespace evflow::ldi {

namespace {

// EDI's double integral of every view, for the regression's targets.
std::vector<std::unique_ptr<events::EdiIntegrator>> edi_per_view(const EventStream& stream, const GpuEvents& events,
                                                                 const events::EdiThresholds& th) {
  std::vector<std::unique_ptr<events::EdiIntegrator>> out;
  for (size_t v = 0; v < events.window_count(); ++v)
    out.push_back(std::make_unique<events::EdiIntegrator>(stream, events.window(v).t0, events.window(v).t1, th));
  return out;
}

// The targets of one step: D(t_i) over the crop, frame after frame.
std::vector<float> crop_targets(const events::EdiIntegrator& edi, const std::vector<double>& times, const Crop& crop) {
  std::vector<float> out;
  for (double t : times) {
    const std::vector<double> d = edi.double_integral(t);
    for (uint32_t y = 0; y < crop.h; ++y)
      for (uint32_t x = 0; x < crop.w; ++x) out.push_back(float(d[size_t(crop.y + y) * edi.width() + crop.x + x]));
  }
  return out;
}

double regression_value(const std::vector<float>& e, const std::vector<float>& d) {
  double s = 0;
  for (size_t i = 0; i < d.size(); ++i) s += std::pow(std::log(double(e[i])) - std::log(double(d[i])), 2);
  return s / double(d.size());
}

}  // namespace

PrefitReport prefit_to_edi(gpu::Context& ctx, LdiModel& model, const EventStream& stream, const GpuEvents& events,
                           const PrefitOptions& o) {
  PrefitReport report;
  if (o.steps == 0) return report;
  if (o.frames == 0 || o.frames > model.max_frames())
    throw std::invalid_argument("LDI pre-fit: " + std::to_string(o.frames) + " frames per step, the model takes 1 to " +
                                std::to_string(model.max_frames()));
  if (events.window_count() == 0) throw std::invalid_argument("LDI pre-fit: no views");
  const auto edi = edi_per_view(stream, events, o.thresholds);
  Adam adam(ctx, AdamOptions{0.9, 0.999, 1e-8});
  model.add_to(adam, o.lr);
  const uint64_t n = uint64_t(o.frames) * model.pixels();
  gpu::Buffer ones(ctx, 3 * model.pixels() * 4, "ldi_prefit_blurry"), target(ctx, n * 4, "ldi_prefit_target");
  ones.write(std::vector<float>(3 * model.pixels(), 1.0f));
  gpu::Commands cmd(ctx);
  std::mt19937_64 rng(o.seed * 0x9E3779B97F4A7C15ull + 0x51ED27u);
  for (uint32_t s = 0; s < o.steps; ++s) {
    const size_t view = s % events.window_count();
    const EventWindow& win = events.window(view);
    const Crop crop{uint32_t(rng() % (events.width() - model.crop_w() + 1)),
                    uint32_t(rng() % (events.height() - model.crop_h() + 1)), model.crop_w(), model.crop_h()};
    std::vector<double> times;
    std::uniform_real_distribution<double> u(win.t0, win.t1);
    for (uint32_t i = 0; i < o.frames; ++i) times.push_back(u(rng));
    const std::vector<float> d = crop_targets(*edi[view], times, crop);
    target.write(d);
    model.forward(cmd, view, times, crop, ones);
    model.backward_from_target(cmd, target, 1.0f / float(n));
    adam.step(cmd);
    cmd.submit();
    if (s == 0 || s + 1 == o.steps) {
      const double value = regression_value(model.integral().read<float>(n), d);
      (s == 0 ? report.first_loss : report.last_loss) = value;
    }
  }
  report.steps = o.steps;
  return report;
}

}  // namespace evflow::ldi
