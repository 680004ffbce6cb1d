#include "nn/tensor.h"

#include <algorithm>
#include <stdexcept>

namespace evflow::nn {

std::string Shape::str() const {
  const std::string chw = std::to_string(c) + "x" + std::to_string(h) + "x" + std::to_string(w);
  return n == 1 ? chw : std::to_string(n) + "x" + chw;
}

Tensor::Tensor(gpu::Context& ctx, Shape shape, std::string name) : shape_(shape) {
  ctx.check_binding_size(shape.count() * 4, "tensor " + name + " (" + shape.str() + ")");
  buffer_ = gpu::Buffer(ctx, std::max<uint64_t>(shape.count() * 4, 4), std::move(name));
}

void Tensor::upload(const std::vector<float>& values) {
  if (values.size() != count())
    throw std::invalid_argument("tensor " + name() + " (" + shape_.str() + "): " + std::to_string(values.size()) +
                                " values given, " + std::to_string(count()) + " expected");
  buffer_.write(values);
}

std::vector<float> Tensor::download() const { return buffer_.read<float>(count()); }

void require_shape(const Tensor& t, const Shape& shape, const std::string& what) {
  if (t.shape() != shape)
    throw std::invalid_argument(what + ": " + t.name() + " is " + t.shape().str() + ", expected " + shape.str());
}

}  // namespace evflow::nn
