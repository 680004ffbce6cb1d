#include "nn/conv_stack.h"

#include <stdexcept>

#include "nn/layers.h"

namespace evflow::nn {

ConvStack::ConvStack(gpu::Context& ctx, const std::vector<uint32_t>& widths, uint32_t height, uint32_t width,
                     const std::string& name)
    : name_(name) {
  if (widths.size() < 2) throw std::invalid_argument("conv stack " + name + ": needs at least one layer");
  input_ = Tensor(ctx, {widths[0], height, width}, name + ".input");
  input_grad_ = Tensor(ctx, input_.shape(), name + ".input_grad");
  for (size_t i = 0; i + 1 < widths.size(); ++i) {
    const std::string n = name + "." + std::to_string(i);
    convs_.push_back(std::make_unique<Conv2d>(ctx, ConvSpec{widths[i], widths[i + 1], 3, 1}, n));
    const Shape s{widths[i + 1], height, width};
    z_.emplace_back(ctx, s, n + ".out");
    if (i + 2 < widths.size()) a_.emplace_back(ctx, s, n + ".relu");
    grad_.emplace_back(ctx, s, n + ".grad");
  }
}

void ConvStack::init_he(uint64_t seed) {
  for (size_t i = 0; i < convs_.size(); ++i) convs_[i]->init_he(seed + i);
}

void ConvStack::forward(gpu::Commands& cmd, const std::string& mark) {
  for (size_t i = 0; i < convs_.size(); ++i) {
    convs_[i]->forward(cmd, i ? a_[i - 1] : input_, z_[i]);
    if (i + 1 < convs_.size()) relu_forward(cmd, z_[i], a_[i]);
    if (!mark.empty()) cmd.mark(mark + " " + std::to_string(i));
  }
}

void ConvStack::backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params, const std::string& mark) {
  for (size_t i = convs_.size(); i-- > 0;) {
    if (i + 1 < convs_.size()) relu_backward(cmd, a_[i], grad_[i], grad_[i]);
    const Tensor* dx = i ? &grad_[i - 1] : (input_grad ? &input_grad_ : nullptr);
    convs_[i]->backward(cmd, i ? a_[i - 1] : input_, grad_[i], dx, false, accumulate_params);
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
