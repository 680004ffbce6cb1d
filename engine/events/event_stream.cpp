#include "events/event_stream.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace evflow {

void EventStream::validate(const std::string& source) const {
  const size_t n = t.size();
  if (x.size() != n || y.size() != n || p.size() != n)
    throw std::runtime_error(source + ": event arrays differ in length (x " + std::to_string(x.size()) + ", y " +
                             std::to_string(y.size()) + ", t " + std::to_string(n) + ", p " + std::to_string(p.size()) +
                             ")");
  for (size_t i = 0; i < n; ++i) {
    if (x[i] >= width || y[i] >= height)
      throw std::runtime_error(source + ": event " + std::to_string(i) + " at (" + std::to_string(x[i]) + ", " +
                               std::to_string(y[i]) + ") is outside the " + std::to_string(width) + "x" +
                               std::to_string(height) + " sensor");
    if (p[i] != 1 && p[i] != -1)
      throw std::runtime_error(source + ": event " + std::to_string(i) + " has polarity " + std::to_string(p[i]) +
                               " (expected +1 or -1)");
    if (!std::isfinite(t[i]))
      throw std::runtime_error(source + ": event " + std::to_string(i) + " has a non-finite timestamp");
    if (i && t[i] < t[i - 1])
      throw std::runtime_error(source + ": timestamps are not sorted: event " + std::to_string(i) +
                               " (t = " + std::to_string(t[i]) + ") comes before event " + std::to_string(i - 1) +
                               " (t = " + std::to_string(t[i - 1]) + ")");
  }
}

std::pair<size_t, size_t> EventStream::window(double t0, double t1) const {
  auto a = std::lower_bound(t.begin(), t.end(), t0) - t.begin();
  auto b = std::lower_bound(t.begin(), t.end(), t1) - t.begin();
  return {static_cast<size_t>(a), static_cast<size_t>(std::max(a, b))};
}

}  // namespace evflow
