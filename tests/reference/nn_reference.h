// Double-precision CPU references of the neural layers (engine/nn): NCHW with N = 1.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

namespace evflow::ref {

struct NnTensor {
  uint32_t c = 0, h = 0, w = 0;
  std::vector<double> v;
  NnTensor() = default;
  NnTensor(uint32_t c_, uint32_t h_, uint32_t w_) : c(c_), h(h_), w(w_), v(size_t(c_) * h_ * w_, 0.0) {}
  double& at(uint32_t ch, uint32_t y, uint32_t x) { return v[(size_t(ch) * h + y) * w + x]; }
  double at(uint32_t ch, uint32_t y, uint32_t x) const { return v[(size_t(ch) * h + y) * w + x]; }
};

// KxK convolution, padding K / 2, the given stride; weights [out_c][in_c][K][K].
NnTensor nn_conv2d(const NnTensor& x, const std::vector<double>& weight, const std::vector<double>& bias,
                   uint32_t out_c, uint32_t ksize, uint32_t stride);
NnTensor nn_relu(const NnTensor& x);
NnTensor nn_sigmoid(const NnTensor& x);
// x2 nearest up-sampling to out_h x out_w.
NnTensor nn_upsample(const NnTensor& x, uint32_t out_h, uint32_t out_w);

// Central finite differences of f at every entry of v: (f(v + h e_i) - f(v - h e_i)) / 2h.
std::vector<double> nn_central_differences(std::vector<double>& v, const std::function<double()>& f, double h);

double nn_dot(const NnTensor& a, const std::vector<double>& b);

}  // namespace evflow::ref
