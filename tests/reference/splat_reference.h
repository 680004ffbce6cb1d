// Double-precision CPU reference of the Gaussian splat rasterizer (docs/rasterizer.md), the
// finite-difference harness the GPU forward/backward is tested against.
//
// Everything is computed in double: the float cloud is converted once to a double copy, and
// finite differences perturb that copy (a perturbed value is never rounded back to float).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "splat/gaussians.h"

namespace evflow::reference {

struct RenderOutput {
  uint32_t width = 0, height = 0;
  std::vector<double> rgb;    // planar 3*H*W: rgb[c*H*W + y*W + x]
  std::vector<double> alpha;  // H*W
  std::vector<double> depth;  // H*W, 0 where nothing was blended
};

// The SH constants of 3DGS (Inria computeColorFromSH).
inline constexpr double kShC0 = 0.28209479177387814;
inline constexpr double kShC1 = 0.4886025119029199;

RenderOutput render(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings);

// L = sum(v_rgb * rgb) + sum(v_alpha * alpha), all in double. v_rgb is 3*H*W planar, v_alpha H*W.
double weighted_loss(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings,
                     const std::vector<float>& v_rgb, const std::vector<float>& v_alpha);

enum class Param { Mean, LogScale, Quat, OpacityLogit, Sh };

// Number of components of a parameter: Mean/LogScale 3, Quat 4, OpacityLogit 1, Sh K*3.
int param_components(Param p, const GaussianCloud& cloud);

// Central finite differences of weighted_loss.
//
// Cost. The constructor projects every Gaussian once, sorts them by depth (stable: ties by
// lower index), bins them into 8x8-pixel tiles and composites every pixel once to record where
// its transmittance stop happened: about one full render. param() re-projects only the perturbed
// Gaussian (at +h and -h) and re-composites only pixels inside the union of its two perturbed
// bounding boxes, skipping those where neither perturbed version reaches alpha >= 1/255 or where
// the base render stopped in front of all three versions (original, +h, -h): there both
// evaluations are bitwise equal, so the difference is exactly 0. The two evaluations of a pixel
// share their walk up to the perturbed Gaussian, and each pixel visits only its tile's candidate
// list. One param() thus costs about (touched pixels) x (candidates per pixel), independent of N
// for small Gaussians and at most about two full renders for one covering the whole image. The
// result equals a full re-render FD (param_full_render) bit for bit when the compiler does not
// contract differently: every pixel sees the same blend sequence, skipped pixels contribute
// exact zeros, and pixel differences are summed in the same order. pose() re-projects and re-renders
// everything: 6 parameters x 2 = 12 full renders.
// Measured (one core, 2,000 Gaussians of random_scene at 160x120, SH degree 3): render ~18 ms,
// constructor ~17 ms, param() ~0.6 ms on average (~0.2 ms typical, ~10 ms for the 3% very large
// Gaussians), pose() ~0.2 s.
// All methods are const and keep no mutable state: one object may be used from several threads.
class FiniteDifferences {
 public:
  FiniteDifferences(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings,
                    std::vector<float> v_rgb, std::vector<float> v_alpha);

  // dL/d(param component) of Gaussian `gaussian`, central difference with step h.
  // component: Mean/LogScale 0..2, Quat 0..3 (w,x,y,z), OpacityLogit 0, Sh k*3+c.
  double param(Param p, size_t gaussian, int component, double h) const;
  // dL/d(delta_i), delta = (rho, phi) in se(3), via Camera::perturbed(+-h e_i).
  std::array<double, 6> pose(double h) const;

  // The same central difference as param(), computed by re-rendering the whole image (slow).
  // Exists to test that the local re-render of param() is exact.
  double param_full_render(Param p, size_t gaussian, int component, double h) const;

  // Loss of the unperturbed scene (equals weighted_loss up to summation order).
  double loss() const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace evflow::reference
