#include "events/binned_events.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "events/events_layout.h"

namespace evflow {

namespace {

// Position of t in bin units, snapped to a bin edge when within 1e-9 of one.
double bin_position(double t, const EventWindow& w, uint32_t bins) {
  const double p = (t - w.t0) / (w.t1 - w.t0) * bins;
  const double edge = std::round(p);
  return std::abs(p - edge) <= 1e-9 ? edge : p;
}

void check_window(const EventWindow& w, size_t index, const std::string& source) {
  if (!(std::isfinite(w.t0) && std::isfinite(w.t1)) || w.t1 <= w.t0)
    throw std::runtime_error(source + ": exposure window " + std::to_string(index) + " [" + std::to_string(w.t0) +
                             ", " + std::to_string(w.t1) + ") is empty or not finite");
}

}  // namespace

std::vector<BinWeight> bin_weights(double t0, double t1, const EventWindow& window, uint32_t bins) {
  const double p0 = std::clamp(bin_position(t0, window, bins), 0.0, double(bins));
  const double p1 = std::clamp(bin_position(t1, window, bins), 0.0, double(bins));
  std::vector<BinWeight> out;
  for (uint32_t b = uint32_t(std::floor(p0)); b < bins && double(b) < p1; ++b) {
    const double w = std::min(p1, double(b) + 1) - std::max(p0, double(b));
    if (w > 0) out.push_back({b, w});
  }
  return out;
}

BinnedEvents::BinnedEvents(gpu::Context& ctx, const std::vector<float>& counts, uint32_t bins, uint32_t width,
                           uint32_t height, const std::vector<EventWindow>& windows, const std::string& source)
    : width_(width), height_(height), bins_(bins), windows_(windows), binned_(ctx, 16, "events_binned") {
  const uint64_t expect = uint64_t(windows.size()) * bins * width * height;
  if (bins == 0 || width == 0 || height == 0 || counts.size() != expect)
    throw std::runtime_error(source + ": binned event counts hold " + std::to_string(counts.size()) +
                             " values, expected " + std::to_string(windows.size()) + " views x " +
                             std::to_string(bins) + " bins x " + std::to_string(width) + "x" + std::to_string(height) +
                             " pixels");
  for (size_t w = 0; w < windows.size(); ++w) check_window(windows[w], w, source);
  for (float c : counts)
    if (!std::isfinite(c)) throw std::runtime_error(source + ": a binned event count is not finite");
  ctx.check_binding_size(expect * 4, source + ": binned event counts of the training views");
  binned_.ensure(std::max<uint64_t>(expect * 4, 16));
  binned_.write(counts);
}

void BinnedEvents::accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                              uint32_t plane) const {
  if (w >= windows_.size())
    throw std::out_of_range("BinnedEvents: window " + std::to_string(w) + " of " + std::to_string(windows_.size()));
  const uint64_t hw = uint64_t(width_) * height_;
  if (counts.size() < (uint64_t(plane) + 1) * 2 * hw * 4)
    throw std::invalid_argument("BinnedEvents::accumulate: " + counts.name() + " has no plane " +
                                std::to_string(plane));
  for (const BinWeight& b : bin_weights(t0, t1, windows_[w], bins_)) {
    shaderio::BinnedAccumulatePC pc{
        uint32_t((uint64_t(w) * bins_ + b.bin) * hw), width_, height_, plane, float(b.weight), 0, 0, 0};
    cmd.dispatch("events/binned_accumulate",
                 {{shaderio::kBinnedAccumulateBindBinned, binned_}, {shaderio::kBinnedAccumulateBindCounts, counts}},
                 pc, cmd.linear_groups(gpu::Commands::div_up(hw, shaderio::kEventGroupSize)));
  }
}

}  // namespace evflow
