#include "events/gpu_events.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "events/events_layout.h"

namespace evflow {

GpuEvents::GpuEvents(gpu::Context& ctx, const EventStream& stream, const std::vector<EventWindow>& windows,
                     const std::string& source)
    : width_(stream.width), height_(stream.height), windows_(windows), packed_(ctx, 16, "events_packed") {
  if (stream.width > shaderio::kEventMaxCoord + 1 || stream.height > shaderio::kEventMaxCoord + 1)
    throw std::runtime_error(source + ": sensor " + std::to_string(stream.width) + "x" + std::to_string(stream.height) +
                             " is larger than the 32768x32768 the GPU event format holds");
  std::vector<uint32_t> packed;
  first_.push_back(0);
  for (size_t w = 0; w < windows.size(); ++w) {
    const EventWindow& win = windows[w];
    if (!(std::isfinite(win.t0) && std::isfinite(win.t1)) || win.t1 <= win.t0)
      throw std::runtime_error(source + ": exposure window " + std::to_string(w) + " [" + std::to_string(win.t0) +
                               ", " + std::to_string(win.t1) + ") is empty or not finite");
    auto [a, b] = stream.window(win.t0, win.t1);
    for (size_t i = a; i < b; ++i) {
      packed.push_back(uint32_t(stream.x[i]) | (uint32_t(stream.y[i]) << shaderio::kEventCoordBits) |
                       (stream.p[i] > 0 ? shaderio::kEventPositiveBit : 0u));
      times_.push_back(stream.t[i]);
    }
    first_.push_back(packed.size());
  }
  const uint64_t bytes = std::max<uint64_t>(packed.size() * 4, 16);
  if (packed.size() > 0xFFFFFFFFull)
    throw std::runtime_error(source + ": more than 2^32 events in the training windows");
  ctx.check_binding_size(bytes, source + ": events of the training exposures");
  packed_.ensure(bytes);
  if (!packed.empty()) packed_.write(packed);
}

std::pair<uint32_t, uint32_t> GpuEvents::range(size_t w, double t0, double t1) const {
  if (w >= windows_.size())
    throw std::out_of_range("GpuEvents: window " + std::to_string(w) + " of " + std::to_string(windows_.size()));
  auto begin = times_.begin() + std::ptrdiff_t(first_[w]), end = times_.begin() + std::ptrdiff_t(first_[w + 1]);
  auto a = std::lower_bound(begin, end, t0), b = std::lower_bound(begin, end, t1);
  if (b < a) b = a;
  return {uint32_t(a - times_.begin()), uint32_t(b - times_.begin())};
}

void GpuEvents::accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                           uint32_t plane) const {
  const uint64_t hw = uint64_t(width_) * height_;
  if (counts.size() < (uint64_t(plane) + 1) * 2 * hw * 4)
    throw std::invalid_argument("GpuEvents::accumulate: " + counts.name() + " has no plane " + std::to_string(plane));
  auto [first, last] = range(w, t0, t1);
  if (last == first) return;
  shaderio::EventAccumulatePC pc{first, last - first, width_, height_, plane, 0, 0, 0};
  cmd.dispatch("events/accumulate",
               {{shaderio::kEventAccumulateBindPacked, packed_}, {shaderio::kEventAccumulateBindCounts, counts}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(last - first, shaderio::kEventGroupSize)));
}

}  // namespace evflow
