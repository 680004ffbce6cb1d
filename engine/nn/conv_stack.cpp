#include "nn/conv_stack.h"

#include <algorithm>
#include <stdexcept>

#include "nn/layers.h"

namespace evflow::nn {

ConvStack::ConvStack(gpu::Context& ctx, const std::vector<uint32_t>& widths, uint32_t height, uint32_t width,
                     const std::string& name, uint32_t batch)
    : name_(name) {
  if (widths.size() < 2) throw std::invalid_argument("conv stack " + name + ": needs at least one layer");
  if (batch == 0) throw std::invalid_argument("conv stack " + name + ": a batch of 0 images");
  input_ = Tensor(ctx, {widths[0], height, width, batch}, name + ".input");
  input_grad_ = Tensor(ctx, input_.shape(), name + ".input_grad");
  for (size_t i = 0; i + 1 < widths.size(); ++i) {
    const std::string n = name + "." + std::to_string(i);
    convs_.push_back(std::make_unique<Conv2d>(ctx, ConvSpec{widths[i], widths[i + 1], 3, 1}, n));
    convs_.back()->reserve({widths[i], height, width, batch});
    const Shape s{widths[i + 1], height, width, batch};
    z_.emplace_back(ctx, s, n + ".out");
    if (i + 2 < widths.size()) a_.emplace_back(ctx, s, n + ".relu");
    grad_.emplace_back(ctx, s, n + ".grad");
  }
}

uint64_t ConvStack::bytes_per_image(const std::vector<uint32_t>& widths, uint32_t height, uint32_t width) {
  uint64_t channels = widths.empty() ? 0 : 2ull * widths[0];  // the input and its gradient
  for (size_t i = 1; i < widths.size(); ++i) channels += uint64_t(widths[i]) * (i + 1 < widths.size() ? 3 : 2);
  return channels * height * width * 4;
}

uint32_t ConvStack::widest(const std::vector<uint32_t>& widths) {
  uint32_t w = 0;
  for (uint32_t v : widths) w = std::max(w, v);
  return w;
}

void ConvStack::init_he(uint64_t seed) {
  for (size_t i = 0; i < convs_.size(); ++i) convs_[i]->init_he(seed + i);
}

void ConvStack::forward(gpu::Commands& cmd, const std::string& mark, uint32_t images) {
  for (size_t i = 0; i < convs_.size(); ++i) {
    convs_[i]->forward(cmd, i ? a_[i - 1] : input_, z_[i], images);
    if (i + 1 < convs_.size()) relu_forward(cmd, z_[i], a_[i], images);
    if (!mark.empty()) cmd.mark(mark + " " + std::to_string(i));
  }
}

void ConvStack::backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params, const std::string& mark,
                         uint32_t images) {
  for (size_t i = convs_.size(); i-- > 0;) {
    if (i + 1 < convs_.size()) relu_backward(cmd, a_[i], grad_[i], grad_[i], false, images);
    const Tensor* dx = i ? &grad_[i - 1] : (input_grad ? &input_grad_ : nullptr);
    convs_[i]->backward(cmd, i ? a_[i - 1] : input_, grad_[i], dx, false, accumulate_params, images);
    if (!mark.empty()) cmd.mark(mark + " " + std::to_string(i));
  }
}

void ConvStack::add_to(Adam& adam, float lr) {
  for (auto& c : convs_) c->add_to(adam, lr);
}

void ConvStack::save(SafetensorsFile& file) const {
  for (auto& c : convs_) {
    const ConvSpec& s = c->spec();
    file.tensors.push_back({c->name() + ".weight", {s.out_c, s.in_c, s.ksize, s.ksize}, c->weight_values()});
    file.tensors.push_back({c->name() + ".bias", {s.out_c}, c->bias_values()});
  }
}

void ConvStack::load(const SafetensorsFile& file, const std::string& source) {
  for (auto& c : convs_) {
    const NamedTensor* w = file.find(c->name() + ".weight");
    const NamedTensor* b = file.find(c->name() + ".bias");
    if (!w || !b) throw std::runtime_error(source + ": no weights for layer " + c->name());
    const ConvSpec& s = c->spec();
    if (w->shape != std::vector<uint64_t>{s.out_c, s.in_c, s.ksize, s.ksize} ||
        b->shape != std::vector<uint64_t>{s.out_c})
      throw std::runtime_error(source + ": layer " + c->name() + " has weights of another shape");
    c->set_parameters(w->values, b->values);
  }
}

}  // namespace evflow::nn
