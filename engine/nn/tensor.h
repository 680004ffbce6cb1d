// A tensor on the device: a float32 storage buffer and its shape, NCHW: channel k at (x, y) of
// image b of a batch of n images of c channels is element ((b * c + k) * h + y) * w + x.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/buffer.h"

namespace evflow::nn {

struct Shape {
  uint32_t c = 0, h = 0, w = 0;
  uint32_t n = 1;  // images in the batch
  uint64_t count() const { return uint64_t(n) * c * h * w; }
  uint64_t pixels() const { return uint64_t(h) * w; }  // of one image
  Shape image() const { return {c, h, w, 1}; }
  Shape batch(uint32_t images) const { return {c, h, w, images}; }
  bool operator==(const Shape& o) const { return c == o.c && h == o.h && w == o.w && n == o.n; }
  bool operator!=(const Shape& o) const { return !(*this == o); }
  std::string str() const;  // "CxHxW", "NxCxHxW" for a batch
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
