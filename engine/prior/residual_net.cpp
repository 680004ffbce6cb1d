#include "prior/residual_net.h"

#include <cstdio>
#include <stdexcept>

#include "nn/layers.h"

namespace evflow::prior {

std::string ResidualNetSpec::str() const {
  return "residual-unet frames=" + std::to_string(frames) + " width=" + std::to_string(width);
}

ResidualNet::Level ResidualNet::make_level(gpu::Context& ctx, nn::ConvSpec s, const std::string& name, nn::Shape in,
                                           bool relu) {
  Level l;
  l.conv = std::make_unique<nn::Conv2d>(ctx, s, "prior." + name);
  const nn::Shape out = l.conv->output_shape(in);
  l.z = nn::Tensor(ctx, out, name + ".z");
  if (relu) l.a = nn::Tensor(ctx, out, name + ".a");
  l.grad = nn::Tensor(ctx, out, name + ".grad");
  return l;
}

ResidualNet::ResidualNet(gpu::Context& ctx, const ResidualNetSpec& spec, uint32_t height, uint32_t width)
    : spec_(spec) {
  if (spec.frames < 3 || spec.frames % 2 == 0 || spec.width == 0)
    throw std::invalid_argument("residual net: needs an odd frame count >= 3 and a width > 0, got " + spec.str());
  const uint32_t w = spec.width;
  input_ = nn::Tensor(ctx, {spec.in_channels(), height, width}, "prior.input");
  input_grad_ = nn::Tensor(ctx, input_.shape(), "prior.input_grad");
  enc0_ = make_level(ctx, {spec.in_channels(), w, 3, 1}, "enc0", input_.shape(), true);
  down1_ = make_level(ctx, {w, 2 * w, 3, 2}, "down1", enc0_.z.shape(), true);
  enc1_ = make_level(ctx, {2 * w, 2 * w, 3, 1}, "enc1", down1_.z.shape(), true);
  down2_ = make_level(ctx, {2 * w, 4 * w, 3, 2}, "down2", enc1_.z.shape(), true);
  enc2_ = make_level(ctx, {4 * w, 4 * w, 3, 1}, "enc2", down2_.z.shape(), true);
  const nn::Shape half = enc1_.z.shape(), full = enc0_.z.shape();
  up1_ = nn::Tensor(ctx, {4 * w, half.h, half.w}, "up1");
  cat1_ = nn::Tensor(ctx, nn::concat_shape(up1_.shape(), half), "cat1");
  dec1_ = make_level(ctx, {6 * w, 2 * w, 3, 1}, "dec1", cat1_.shape(), true);
  up0_ = nn::Tensor(ctx, {2 * w, full.h, full.w}, "up0");
  cat0_ = nn::Tensor(ctx, nn::concat_shape(up0_.shape(), full), "cat0");
  dec0_ = make_level(ctx, {3 * w, w, 3, 1}, "dec0", cat0_.shape(), true);
  out_ = make_level(ctx, {w, spec.out_channels(), 1, 1}, "out", dec0_.z.shape(), false);
  up1_grad_ = nn::Tensor(ctx, up1_.shape(), "up1.grad");
  cat1_grad_ = nn::Tensor(ctx, cat1_.shape(), "cat1.grad");
  up0_grad_ = nn::Tensor(ctx, up0_.shape(), "up0.grad");
  cat0_grad_ = nn::Tensor(ctx, cat0_.shape(), "cat0.grad");
}

std::vector<nn::Conv2d*> ResidualNet::layers() {
  std::vector<nn::Conv2d*> v;
  for (Level* l : {&enc0_, &down1_, &enc1_, &down2_, &enc2_, &dec1_, &dec0_, &out_}) v.push_back(l->conv.get());
  return v;
}

uint64_t ResidualNet::parameter_count() const {
  uint64_t n = 0;
  for (const Level* l : {&enc0_, &down1_, &enc1_, &down2_, &enc2_, &dec1_, &dec0_, &out_})
    n += l->conv->weight_count() + l->conv->spec().out_c;
  return n;
}

void ResidualNet::init_he(uint64_t seed) {
  const auto convs = layers();
  for (size_t i = 0; i + 1 < convs.size(); ++i) convs[i]->init_he(seed + i);
  nn::Conv2d& out = *convs.back();
  out.set_parameters(std::vector<float>(out.weight_count(), 0.0f), std::vector<float>(out.spec().out_c, 0.0f));
}

void ResidualNet::forward(gpu::Commands& cmd) {
  auto level = [&](Level& l, const nn::Tensor& in) {
    l.conv->forward(cmd, in, l.z);
    if (l.a.count()) nn::relu_forward(cmd, l.z, l.a);
  };
  level(enc0_, input_);
  level(down1_, enc0_.a);
  level(enc1_, down1_.a);
  level(down2_, enc1_.a);
  level(enc2_, down2_.a);
  nn::upsample_forward(cmd, enc2_.a, up1_);
  nn::concat_forward(cmd, up1_, enc1_.a, cat1_);
  level(dec1_, cat1_);
  nn::upsample_forward(cmd, dec1_.a, up0_);
  nn::concat_forward(cmd, up0_, enc0_.a, cat0_);
  level(dec0_, cat0_);
  level(out_, dec0_.a);
}

// From l.grad (the gradient at the level's activation, or its output for the last level):
// through the ReLU in place, then the convolution into dx.
void ResidualNet::conv_backward(gpu::Commands& cmd, Level& l, const nn::Tensor& in, const nn::Tensor* dx,
                                bool accumulate_input, bool accumulate_params) {
  if (l.a.count()) nn::relu_backward(cmd, l.a, l.grad, l.grad);
  l.conv->backward(cmd, in, l.grad, dx, accumulate_input, accumulate_params);
}

void ResidualNet::backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params) {
  const bool acc = accumulate_params;
  conv_backward(cmd, out_, dec0_.a, &dec0_.grad, false, acc);
  conv_backward(cmd, dec0_, cat0_, &cat0_grad_, false, acc);
  nn::concat_backward(cmd, cat0_grad_, up0_grad_, enc0_.grad);  // enc0's skip share
  nn::upsample_backward(cmd, up0_grad_, dec1_.grad);
  conv_backward(cmd, dec1_, cat1_, &cat1_grad_, false, acc);
  nn::concat_backward(cmd, cat1_grad_, up1_grad_, enc1_.grad);  // enc1's skip share
  nn::upsample_backward(cmd, up1_grad_, enc2_.grad);
  conv_backward(cmd, enc2_, down2_.a, &down2_.grad, false, acc);
  conv_backward(cmd, down2_, enc1_.a, &enc1_.grad, true, acc);  // adds to the skip share
  conv_backward(cmd, enc1_, down1_.a, &down1_.grad, false, acc);
  conv_backward(cmd, down1_, enc0_.a, &enc0_.grad, true, acc);
  conv_backward(cmd, enc0_, input_, input_grad ? &input_grad_ : nullptr, false, acc);
}

void ResidualNet::add_to(Adam& adam, float lr) {
  for (nn::Conv2d* c : layers()) c->add_to(adam, lr);
}

nn::SafetensorsFile ResidualNet::save() const {
  nn::SafetensorsFile f;
  for (const Level* l : {&enc0_, &down1_, &enc1_, &down2_, &enc2_, &dec1_, &dec0_, &out_}) {
    const nn::ConvSpec& s = l->conv->spec();
    f.tensors.push_back({l->conv->name() + ".weight", {s.out_c, s.in_c, s.ksize, s.ksize}, l->conv->weight_values()});
    f.tensors.push_back({l->conv->name() + ".bias", {s.out_c}, l->conv->bias_values()});
  }
  f.metadata["architecture"] = spec_.str();
  return f;
}

void ResidualNet::load(const nn::SafetensorsFile& file, const std::string& source) {
  const auto arch = file.metadata.find("architecture");
  if (arch == file.metadata.end() || arch->second != spec_.str())
    throw std::runtime_error(source + ": architecture '" + (arch == file.metadata.end() ? "" : arch->second) +
                             "', expected '" + spec_.str() + "'");
  for (nn::Conv2d* c : layers()) {
    const nn::NamedTensor* w = file.find(c->name() + ".weight");
    const nn::NamedTensor* b = file.find(c->name() + ".bias");
    if (!w || !b) throw std::runtime_error(source + ": no weights for layer " + c->name());
    const nn::ConvSpec& s = c->spec();
    if (w->shape != std::vector<uint64_t>{s.out_c, s.in_c, s.ksize, s.ksize} ||
        b->shape != std::vector<uint64_t>{s.out_c})
      throw std::runtime_error(source + ": layer " + c->name() + " has weights of another shape");
    c->set_parameters(w->values, b->values);
  }
}

void ResidualNet::copy_weights_from(const ResidualNet& other) { load(other.save(), "residual net copy"); }

std::unique_ptr<ResidualNet> load_residual_net(gpu::Context& ctx, const std::string& path, uint32_t height,
                                               uint32_t width) {
  const nn::SafetensorsFile file = nn::load_safetensors(path);
  const auto arch = file.metadata.find("architecture");
  if (arch == file.metadata.end())
    throw std::runtime_error(path + ": no 'architecture' metadata (not a residual prior's weights)");
  ResidualNetSpec spec;
  if (std::sscanf(arch->second.c_str(), "residual-unet frames=%u width=%u", &spec.frames, &spec.width) != 2)
    throw std::runtime_error(path + ": architecture '" + arch->second + "' is not a residual U-Net");
  auto net = std::make_unique<ResidualNet>(ctx, spec, height, width);
  net->load(file, path);
  return net;
}

}  // namespace evflow::prior
