// A tensor on the device: a float32 storage buffer and its shape, NCHW with N = 1 (element
// (c, y, x) at (c * h + y) * w + x).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/buffer.h"

namespace evflow::nn {

struct Shape {
  uint32_t c = 0, h = 0, w = 0;
  uint64_t count() const { return uint64_t(c) * h * w; }
  uint64_t pixels() const { return uint64_t(h) * w; }
  bool operator==(const Shape& o) const { return c == o.c && h == o.h && w == o.w; }
  bool operator!=(const Shape& o) const { return !(*this == o); }
  std::string str() const;  // "CxHxW"
};

class Tensor {
 public:
  Tensor() = default;
  // Throws when the tensor would not fit one storage binding of the device.
  Tensor(gpu::Context& ctx, Shape shape, std::string name);

  const Shape& shape() const { return shape_; }
  uint64_t count() const { return shape_.count(); }
  uint64_t bytes() const { return shape_.count() * 4; }
  const gpu::Buffer& buffer() const { return buffer_; }
  const std::string& name() const { return buffer_.name(); }

  void upload(const std::vector<float>& values);  // exactly count() values
  std::vector<float> download() const;

 private:
  Shape shape_;
  gpu::Buffer buffer_;
};

// Throws std::invalid_argument "<what>: <name> is <shape>, expected <shape>" unless t has `shape`.
void require_shape(const Tensor& t, const Shape& shape, const std::string& what);

}  // namespace evflow::nn
