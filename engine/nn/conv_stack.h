// A plain stack of 3x3 stride-1 convolutions with ReLU after every layer but the last: the LDI
// network's shape (widths 32 -> 64 -> 128 -> 64 -> 16 -> 1 in the paper). It owns its
// activations and their gradients for one input size and a batch of up to `batch` images (NCHW,
// nn/tensor.h), all run by one dispatch per layer; forward and backward are recorded into a
// command batch, optionally with a timing mark after each layer. A backward uses the activations
// of the last forward, over the same images.
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
            const std::string& name, uint32_t batch = 1);

  // Bytes of the tensors one image of a widths x height x width stack holds: what a batch costs.
  static uint64_t bytes_per_image(const std::vector<uint32_t>& widths, uint32_t height, uint32_t width);
  // The largest channel count of its tensors: the one whose batch must fit a storage binding.
  static uint32_t widest(const std::vector<uint32_t>& widths);

  size_t layers() const { return convs_.size(); }
  uint32_t batch() const { return input_.shape().n; }
  Conv2d& layer(size_t i) { return *convs_.at(i); }
  Tensor& input() { return input_; }  // where the caller uploads the input
  const Tensor& output() const { return z_.back(); }
  // Where the caller writes d(loss)/d(output) before backward().
  Tensor& output_grad() { return grad_.back(); }
  // d(loss)/d(input), after a backward() with input_grad.
  const Tensor& input_grad() const { return input_grad_; }

  void init_he(uint64_t seed);  // layer i from seed + i
  // mark: when set, a timing mark "<mark> <i>" after each layer (Commands::mark). images: the
  // first images of the batch to run (0: all); a backward's must be its forward's.
  void forward(gpu::Commands& cmd, const std::string& mark = "", uint32_t images = 0);
  void backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params = false, const std::string& mark = "",
                uint32_t images = 0);
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
