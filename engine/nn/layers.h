// The layers without weights, recorded into a command batch: ReLU, sigmoid, x2 nearest
// up-sampling (shaders/nn) and channel concatenation (buffer copies). Backward functions write
// the input gradient, or add into it with `accumulate` (for a tensor used twice). `images`: run
// over the first images of a batch only (0: all the tensors hold).
#pragma once
#include "gpu/commands.h"
#include "nn/tensor.h"

namespace evflow::nn {

void relu_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images = 0);
// From the forward's output y: dx = dy where y > 0, else 0.
void relu_backward(gpu::Commands& cmd, const Tensor& y, const Tensor& dy, const Tensor& dx, bool accumulate = false,
                   uint32_t images = 0);

void sigmoid_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images = 0);
// From the forward's output y: dx = dy y (1 - y).
void sigmoid_backward(gpu::Commands& cmd, const Tensor& y, const Tensor& dy, const Tensor& dx, bool accumulate = false,
                      uint32_t images = 0);

// y(c, v, u) = x(c, v / 2, u / 2) for y of x's channels and 2h or 2h - 1 rows, 2w or 2w - 1
// columns (so that an odd size down-sampled by a stride-2 convolution comes back to itself).
void upsample_forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y);
void upsample_backward(gpu::Commands& cmd, const Tensor& dy, const Tensor& dx, bool accumulate = false);

// y = [a; b] along channels (a and b of the same size); the backward splits dy into da and db.
Shape concat_shape(const Shape& a, const Shape& b);
void concat_forward(gpu::Commands& cmd, const Tensor& a, const Tensor& b, const Tensor& y);
void concat_backward(gpu::Commands& cmd, const Tensor& dy, const Tensor& da, const Tensor& db);

}  // namespace evflow::nn
