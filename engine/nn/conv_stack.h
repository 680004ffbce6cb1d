// A plain stack of 3x3 stride-1 convolutions with ReLU after every layer but the last: the LDI
// network's shape (widths 32 -> 64 -> 128 -> 64 -> 16 -> 1 in the paper). It owns its
// activations and their gradients for one input size; forward and backward are recorded into a
// command batch, optionally with a timing mark after each layer.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "nn/conv2d.h"
#include "nn/safetensors.h"

namespace evflow::nn {

class ConvStack {
 public:
  // widths: the input's channels, then each layer's output channels.
  ConvStack(gpu::Context& ctx, const std::vector<uint32_t>& widths, uint32_t height, uint32_t width,
            const std::string& name);

  size_t layers() const { return convs_.size(); }
  Conv2d& layer(size_t i) { return *convs_.at(i); }
  Tensor& input() { return input_; }  // where the caller uploads the input
  const Tensor& output() const { return z_.back(); }
  // Where the caller writes d(loss)/d(output) before backward().
  Tensor& output_grad() { return grad_.back(); }
  // d(loss)/d(input), after a backward() with input_grad.
  const Tensor& input_grad() const { return input_grad_; }

  void init_he(uint64_t seed);  // layer i from seed + i
  // mark: when set, a timing mark "<mark> <i>" after each layer (Commands::mark).
  void forward(gpu::Commands& cmd, const std::string& mark = "");
  void backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params = false, const std::string& mark = "");
  void add_to(Adam& adam, float lr);

  // Tensors "<name>.<i>.weight" [out, in, k, k] and "<name>.<i>.bias" [out].
  void save(SafetensorsFile& file) const;
  void load(const SafetensorsFile& file, const std::string& source);

 private:
  std::string name_;
  std::vector<std::unique_ptr<Conv2d>> convs_;
  Tensor input_, input_grad_;
  std::vector<Tensor> z_, grad_;  // per layer: output, its gradient (in place through the ReLU)
  std::vector<Tensor> a_;         // per layer but the last: the ReLU of its output
};

}  // namespace evflow::nn
