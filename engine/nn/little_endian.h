// Floats to little-endian bytes and back: a copy on little-endian hosts, byte swaps elsewhere.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace evflow::nn {

inline bool little_endian_host() {
  const uint32_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

inline void floats_to_le(const float* v, size_t n, char* out) {
  std::memcpy(out, v, n * 4);
  if (!little_endian_host())
    for (size_t i = 0; i < n; ++i) std::reverse(out + 4 * i, out + 4 * i + 4);
}

inline void le_to_floats(const char* in, size_t n, float* v) {
  std::memcpy(v, in, n * 4);
  if (!little_endian_host()) {
    char* b = reinterpret_cast<char*>(v);
    for (size_t i = 0; i < n; ++i) std::reverse(b + 4 * i, b + 4 * i + 4);
  }
}

}  // namespace evflow::nn
