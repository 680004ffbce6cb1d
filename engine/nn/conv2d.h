// A 2-D convolution layer (3x3 or 1x1, padding ksize / 2, stride 1 or 2) with its weights, bias
// and their gradients on the device; forward and backward are recorded into a command batch as
// tiled implicit-GEMM kernels (shaders/nn/nn_layout.h), or on CPU drivers, for 3x3 stride-1
// layers, as the direct convolution (forward and weight gradient with 8 or more output channels,
// input gradient with 8 or more input channels; rows read as vec4s where the width is a multiple
// of 4). Weights are W[out_c][in_c][ky][kx].
//
// The weight gradient is deterministic: partial sums per chunk of output pixels, then a second
// pass adds them in a fixed order (no float atomics).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/commands.h"
#include "nn/tensor.h"
#include "optim/adam.h"

namespace evflow::nn {

struct ConvSpec {
  uint32_t in_c = 1, out_c = 1;
  uint32_t ksize = 3;   // 1 or 3
  uint32_t stride = 1;  // 1 or 2
};

class Conv2d {
 public:
  Conv2d(gpu::Context& ctx, ConvSpec spec, std::string name);

  const ConvSpec& spec() const { return spec_; }
  const std::string& name() const { return name_; }
  uint64_t weight_count() const { return uint64_t(spec_.out_c) * spec_.in_c * spec_.ksize * spec_.ksize; }
  // The output's shape for an input of `in`, as many images (throws when in.c differs from in_c).
  Shape output_shape(const Shape& in) const;
  // Multiply-adds of one forward pass over an input of `in` (the backward costs twice this).
  uint64_t macs(const Shape& in) const;
  // Sizes the weight gradient's partial sums for inputs up to `in` (images included), so that
  // backward() over such inputs never reallocates inside a recorded batch.
  void reserve(const Shape& in);

  // He initialisation of the weights (fan_in = in_c ksize^2), zero bias.
  void init_he(uint64_t seed);
  void set_parameters(const std::vector<float>& weight, const std::vector<float>& bias);
  std::vector<float> weight_values() const { return weight_.read<float>(weight_count()); }
  std::vector<float> bias_values() const { return bias_.read<float>(spec_.out_c); }

  // y = conv(x) + bias, image by image over the first `images` images of x and y (0: all of x's).
  void forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images = 0) const;
  // From dy (the gradient at y): dx (skipped when null; added into with accumulate_input), and
  // the weight and bias gradients summed over the images (added into with accumulate_params,
  // e.g. for weights shared by two calls). The partial sums' buffer grows to the largest input
  // seen: reserve() it, or record a backward over a larger input than before only after the
  // batch that used the smaller one was submitted.
  void backward(gpu::Commands& cmd, const Tensor& x, const Tensor& dy, const Tensor* dx, bool accumulate_input = false,
                bool accumulate_params = false, uint32_t images = 0);

  const gpu::Buffer& weight() const { return weight_; }
  const gpu::Buffer& bias() const { return bias_; }
  const gpu::Buffer& weight_grad() const { return weight_grad_; }
  const gpu::Buffer& bias_grad() const { return bias_grad_; }
  // Adds two groups, "<name>.weight" and "<name>.bias", with learning rate lr.
  void add_to(Adam& adam, float lr) const;

 private:
  void backward_weights(gpu::Commands& cmd, const Shape& in, const Tensor& x, const Tensor& dy, bool accumulate);
  // Whether the direct kernel runs a pass writing `channels` channels.
  bool direct(uint32_t channels) const;
  // The direct kernel from x (in_c channels) to y (out_c), WT from W first (flip: the input
  // gradient's kernel, into weight_tb_).
  void record_direct(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t in_c, uint32_t out_c,
                     const Shape& s, bool flip, bool accumulate) const;
  // The images a pass runs over x (`images`, 0 for all), checked against x's batch.
  Shape run_shape(const Tensor& x, uint32_t images) const;
  uint64_t partial_bytes(const Shape& in, uint32_t* per_split_count) const;
  gpu::Context& ctx_;
  ConvSpec spec_;
  std::string name_;
  gpu::Buffer weight_, bias_, weight_grad_, bias_grad_, partial_;
  gpu::Buffer weight_t_, weight_tb_;  // the direct kernel's WT: forward, input gradient
};

}  // namespace evflow::nn
