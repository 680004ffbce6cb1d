// Events of a DVS sensor, struct-of-arrays, sorted by time.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace evflow {

struct EventStream {
  uint32_t width = 0, height = 0;  // sensor size; every event has x < width, y < height
  std::vector<uint16_t> x, y;
  std::vector<double> t;  // seconds, non-decreasing
  std::vector<int8_t> p;  // +1 (brighter) or -1 (darker)

  size_t size() const { return t.size(); }
  void reserve(size_t n) {
    x.reserve(n);
    y.reserve(n);
    t.reserve(n);
    p.reserve(n);
  }
  void push(uint16_t ex, uint16_t ey, double et, int8_t ep) {
    x.push_back(ex);
    y.push_back(ey);
    t.push_back(et);
    p.push_back(ep);
  }
  // Throws std::runtime_error naming `source` on mismatched array sizes, an event outside the
  // sensor, a polarity other than +-1, a non-finite or decreasing timestamp (with its index).
  void validate(const std::string& source) const;
  // Index range [first, last) of the events with t0 <= t < t1 (binary search).
  std::pair<size_t, size_t> window(double t0, double t1) const;
};

}  // namespace evflow
