#include "reference/residual_net_reference.h"

#include <stdexcept>

namespace evflow::ref {

namespace {

NnTensor conv(const NnTensor& x, const UnetLayer& l) {
  return nn_conv2d(x, l.weight, l.bias, l.out_c, l.ksize, l.stride);
}

NnTensor concat(const NnTensor& a, const NnTensor& b) {
  if (a.h != b.h || a.w != b.w) throw std::invalid_argument("residual_unet: concat of different sizes");
  NnTensor y(a.c + b.c, a.h, a.w);
  std::copy(a.v.begin(), a.v.end(), y.v.begin());
  std::copy(b.v.begin(), b.v.end(), y.v.begin() + a.v.size());
  return y;
}

}  // namespace

NnTensor residual_unet(const NnTensor& x, const std::vector<UnetLayer>& L) {
  if (L.size() != 8) throw std::invalid_argument("residual_unet: 8 layers expected");
  const NnTensor s0 = nn_relu(conv(x, L[0]));
  const NnTensor s1 = nn_relu(conv(nn_relu(conv(s0, L[1])), L[2]));
  const NnTensor bottom = nn_relu(conv(nn_relu(conv(s1, L[3])), L[4]));
  const NnTensor d1 = nn_relu(conv(concat(nn_upsample(bottom, s1.h, s1.w), s1), L[5]));
  const NnTensor d0 = nn_relu(conv(concat(nn_upsample(d1, s0.h, s0.w), s0), L[6]));
  return conv(d0, L[7]);
}

}  // namespace evflow::ref
