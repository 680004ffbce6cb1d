#include "nn/layers.h"

#include <stdexcept>

#include "nn/nn_layout.h"

namespace evflow::nn {

using namespace shaderio;

namespace {

// The values of the first `images` images of t (0: all of them).
uint32_t values(const Tensor& t, uint32_t images, const char* kernel) {
  if (images > t.shape().n)
    throw std::invalid_argument(std::string(kernel) + ": " + std::to_string(images) + " images asked of " + t.name() +
                                " (" + t.shape().str() + ")");
  return uint32_t(images ? t.shape().batch(images).count() : t.count());
}

void elementwise(gpu::Commands& cmd, const char* kernel, const Tensor& in, const Tensor& out, uint32_t images) {
  PointwisePC pc{};
  pc.count = values(out, images, kernel);
  cmd.dispatch(kernel, {{kActFwdBindX, in.buffer()}, {kActFwdBindY, out.buffer()}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(pc.count, kNnGroupSize)));
}

void elementwise_backward(gpu::Commands& cmd, const char* kernel, const Tensor& y, const Tensor& dy, const Tensor& dx,
                          bool accumulate, uint32_t images) {
  require_shape(dy, y.shape(), std::string(kernel) + " output gradient");
  require_shape(dx, y.shape(), std::string(kernel) + " input gradient");
  PointwisePC pc{};
  pc.count = values(y, images, kernel);
  pc.accumulate = accumulate ? 1u : 0u;
  cmd.dispatch(kernel, {{kActBwdBindY, y.buffer()}, {kActBwdBindDy, dy.buffer()}, {kActBwdBindDx, dx.buffer()}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(pc.count, kNnGroupSize)));
}

PointwisePC upsample_pc(const Shape& low, const Shape& high) {
  if (high.c != low.c || high.n != low.n || high.h > 2 * low.h || high.w > 2 * low.w || high.h + 1 < 2 * low.h ||
      high.w + 1 < 2 * low.w)
    throw std::invalid_argument("upsample: " + low.str() + " cannot be up-sampled x2 to " + high.str());
  PointwisePC pc{};
  pc.channels = low.c * low.n, pc.in_h = low.h, pc.in_w = low.w, pc.out_h = high.h, pc.out_w = high.w;
  return pc;
}

}  // namespace

void relu_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images) {
  require_shape(y, x.shape(), "relu output");
  elementwise(cmd, "nn/relu", x, y, images);
}

void relu_backward(gpu::Commands& cmd, const Tensor& y, const Tensor& dy, const Tensor& dx, bool accumulate,
                   uint32_t images) {
  elementwise_backward(cmd, "nn/relu_bwd", y, dy, dx, accumulate, images);
}

void sigmoid_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images) {
  require_shape(y, x.shape(), "sigmoid output");
  elementwise(cmd, "nn/sigmoid", x, y, images);
}

void sigmoid_backward(gpu::Commands& cmd, const Tensor& y, const Tensor& dy, const Tensor& dx, bool accumulate,
                      uint32_t images) {
  elementwise_backward(cmd, "nn/sigmoid_bwd", y, dy, dx, accumulate, images);
}

void upsample_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y) {
  PointwisePC pc = upsample_pc(x.shape(), y.shape());
  pc.count = uint32_t(y.count());
  cmd.dispatch("nn/upsample", {{kActFwdBindX, x.buffer()}, {kActFwdBindY, y.buffer()}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(pc.count, kNnGroupSize)));
}

void upsample_backward(gpu::Commands& cmd, const Tensor& dy, const Tensor& dx, bool accumulate) {
  PointwisePC pc = upsample_pc(dx.shape(), dy.shape());
  pc.count = uint32_t(dx.count());
  pc.accumulate = accumulate ? 1u : 0u;
  cmd.dispatch("nn/upsample_bwd", {{kActBwdBindDy, dy.buffer()}, {kActBwdBindDx, dx.buffer()}}, pc,
               cmd.linear_groups(gpu::Commands::div_up(pc.count, kNnGroupSize)));
}

Shape concat_shape(const Shape& a, const Shape& b) {
  if (a.h != b.h || a.w != b.w) throw std::invalid_argument("concat: sizes differ, " + a.str() + " and " + b.str());
  if (a.n != 1 || b.n != 1) throw std::invalid_argument("concat: batches of images are not supported, " + a.str());
  return {a.c + b.c, a.h, a.w};
}

void concat_forward(gpu::Commands& cmd, const Tensor& a, const Tensor& b, const Tensor& y) {
  require_shape(y, concat_shape(a.shape(), b.shape()), "concat output");
  cmd.copy(a.buffer(), y.buffer(), a.bytes());
  cmd.copy(b.buffer(), y.buffer(), b.bytes(), 0, a.bytes());
}

void concat_backward(gpu::Commands& cmd, const Tensor& dy, const Tensor& da, const Tensor& db) {
  require_shape(dy, concat_shape(da.shape(), db.shape()), "concat output gradient");
  cmd.copy(dy.buffer(), da.buffer(), da.bytes());
  cmd.copy(dy.buffer(), db.buffer(), db.bytes(), da.bytes(), 0);
}

}  // namespace evflow::nn
