#include "ldi/event_bins.h"

#include <stdexcept>
#include <string>

namespace evflow::ldi {

namespace {

using Bounds = std::array<uint32_t, shaderio::kLdiBins + 1>;

void check_time(const GpuEvents& events, size_t view, double t_i) {
  const EventWindow& win = events.window(view);
  if (!(t_i >= win.t0 && t_i <= win.t1))
    throw std::invalid_argument("LDI events: frame time " + std::to_string(t_i) + " outside view " +
                                std::to_string(view) + "'s exposure [" + std::to_string(win.t0) + ", " +
                                std::to_string(win.t1) + "]");
}

// Dispatches ldi/bin_events over the events between bounds[0] and bounds[bins].
void record_bins(gpu::Commands& cmd, const GpuEvents& events, const uint32_t* bounds, uint32_t bins, bool reversed,
                 uint32_t channel_base, const Crop& crop, const gpu::Buffer& counts) {
  const uint32_t n = bounds[bins] - bounds[0];
  if (n == 0) return;
  shaderio::LdiBinPC pc{};
  for (uint32_t k = 0; k <= bins; ++k) pc.bound[k / 4][k % 4] = bounds[k];
  pc.bins = bins;
  pc.reversed = reversed ? 1u : 0u;
  pc.channel_base = channel_base;
  pc.crop_x = crop.x, pc.crop_y = crop.y, pc.crop_w = crop.w, pc.crop_h = crop.h;
  cmd.dispatch("ldi/bin_events",
               {{shaderio::kLdiBinBindPacked, events.packed()}, {shaderio::kLdiBinBindCounts, counts}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(n, shaderio::kLdiGroupSize)));
}

}  // namespace

void check_crop(const Crop& crop, uint32_t width, uint32_t height, const char* what) {
  if (crop.w == 0 || crop.h == 0 || uint64_t(crop.x) + crop.w > width || uint64_t(crop.y) + crop.h > height)
    throw std::invalid_argument(std::string(what) + ": crop " + std::to_string(crop.w) + "x" + std::to_string(crop.h) +
                                " at (" + std::to_string(crop.x) + ", " + std::to_string(crop.y) +
                                ") is empty or leaves the " + std::to_string(width) + "x" + std::to_string(height) +
                                " image");
}

Bounds side_bounds(const GpuEvents& events, size_t view, double t_i, Side side) {
  check_time(events, view, t_i);
  const EventWindow& win = events.window(view);
  const double a = side == Side::After ? t_i : win.t0, b = side == Side::After ? win.t1 : t_i;
  Bounds bounds{};
  for (uint32_t k = 0; k <= shaderio::kLdiBins; ++k) {
    const double t = k == shaderio::kLdiBins ? b : a + (b - a) * k / shaderio::kLdiBins;
    bounds[k] = events.range(view, t, t).first;
  }
  return bounds;
}

void record_side_counts(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t_i, Side side,
                        const Crop& crop, const gpu::Buffer& out, uint32_t slot) {
  check_crop(crop, events.width(), events.height(), "LDI event tensor");
  const uint64_t n = crop.pixels() * shaderio::kLdiChannels;
  if (out.size() < (uint64_t(slot) + 1) * n * 4)
    throw std::invalid_argument("LDI event tensor: " + out.name() + " has no image " + std::to_string(slot) +
                                " of 32 x crop floats");
  const Bounds bounds = side_bounds(events, view, t_i, side);
  record_bins(cmd, events, bounds.data(), shaderio::kLdiBins, side == Side::Before, slot * shaderio::kLdiChannels, crop,
              out);
}

void record_counts_to_float(gpu::Commands& cmd, const gpu::Buffer& out, uint64_t values) {
  if (out.size() < values * 4) throw std::invalid_argument("LDI event tensor: " + out.name() + " is too small");
  shaderio::LdiCountPC pc{uint32_t(values), 0, 0, 0};
  cmd.dispatch("ldi/counts_to_float", {{shaderio::kLdiCountBindValues, out}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(values, shaderio::kLdiGroupSize)));
}

void record_side_tensor(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t_i, Side side,
                        const Crop& crop, const gpu::Buffer& out) {
  check_crop(crop, events.width(), events.height(), "LDI event tensor");
  const uint64_t n = crop.pixels() * shaderio::kLdiChannels;
  if (out.size() < n * 4)
    throw std::invalid_argument("LDI event tensor: " + out.name() + " holds fewer than 32 x crop floats");
  cmd.fill(out, 0u, 0, n * 4);
  record_side_counts(cmd, events, view, t_i, side, crop, out, 0);
  record_counts_to_float(cmd, out, n);
}

void record_crop_counts(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t0, double t1,
                        const Crop& crop, const gpu::Buffer& counts, uint32_t plane) {
  check_crop(crop, events.width(), events.height(), "LDI event counts");
  if (counts.size() < (uint64_t(plane) + 1) * 2 * crop.pixels() * 4)
    throw std::invalid_argument("LDI event counts: " + counts.name() + " has no plane " + std::to_string(plane));
  const auto [first, last] = events.range(view, t0, t1);
  const uint32_t bounds[2] = {first, last};
  record_bins(cmd, events, bounds, 1, false, 2 * plane, crop, counts);
}

}  // namespace evflow::ldi
