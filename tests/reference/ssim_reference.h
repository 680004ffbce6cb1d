// Double-precision CPU references of the image losses and metrics (engine/loss), with the exact
// SSIM definition of shaders/loss/ssim_math.glsl:
//   per channel, 11 x 11 Gaussian window (sigma 1.5, normalised over the full 11 x 11 window),
//   "same"-size zero-padded convolution: window taps falling outside the image are dropped and
//   the remaining weights are not renormalised; C1 = 0.01^2, C2 = 0.03^2; mean over C*H*W.
// Images are planar: img[c*H*W + y*W + x].
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace evflow::reference {

struct ImageDims {
  int channels = 3, height = 0, width = 0;
  size_t count() const { return size_t(channels) * height * width; }
  size_t index(int c, int y, int x) const { return (size_t(c) * height + y) * width + x; }
};

// The normalised 1D taps g[0..10] (the 2D window is g[dy+5] g[dx+5]).
const std::vector<double>& ssim_taps();

// SSIM map (count() values) through separable passes.
std::vector<double> ssim_map(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d);
double ssim_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d);
// SSIM at one pixel, from the 2D window directly (independent of the separable code path).
double ssim_pixel(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x);
// Sum of SSIM over the pixels whose window contains (c, y, x): the only part of sum(SSIM) that
// depends on a[(c, y, x)] (for local finite differences).
double ssim_local_sum(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y,
                      int x);

double l1_mean(const std::vector<double>& a, const std::vector<double>& b);
double mse(const std::vector<double>& a, const std::vector<double>& b);
double psnr(const std::vector<double>& a, const std::vector<double>& b);  // -10 log10(MSE)
// (1 - lambda) L1 + lambda (1 - SSIM)
double blend_loss(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, double lambda);

// Central finite differences (step h, in double) of the losses w.r.t. a[(c, y, x)], evaluated
// locally (only the terms that depend on that pixel).
double fd_ssim_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x,
                    double h = 1e-5);
double fd_l1_mean(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, int c, int y, int x,
                  double h = 1e-6);
double fd_blend_loss(const std::vector<double>& a, const std::vector<double>& b, const ImageDims& d, double lambda,
                     int c, int y, int x, double h = 1e-5);

}  // namespace evflow::reference
