// The per-view camera trajectory over the exposure (paper Sec. 4.1, Eq. 4; REFERENCE.md §2):
// a Bézier curve in SE(3) built as a product of exponentials of weighted se(3) knots,
//
//   T(u) = Exp(B_0(u) xi_0) * Exp(B_1(u) xi_1) * ... * Exp(B_8(u) xi_8),
//   B_j(u) = C(8, j) (1 - u)^(8 - j) u^j,   u = (t - t_start) / exposure in [0, 1],
//
// right-multiplied onto the view's pose: c2w(u) = c2w_view * T(u) (w2c(u) = T(u)^-1 * w2c_view).
// Knots are se(3) vectors (rho, phi), translation first, stored flat as 9 x 6 doubles so that an
// optimizer can update them in place.
//
// Gradients: the rasterizer returns g = dL/d delta for the camera perturbed as
// c2w' = c2w * Exp(delta) (Camera::perturbed). backward() maps g to dL/d xi_j exactly:
//   dL/d xi_j = B_j(u) J_r(B_j(u) xi_j)^T Ad(S_j^-1)^T g,   S_j = Exp(B_{j+1} xi_{j+1}) ... Exp(B_8 xi_8).
// See docs/trajectory.md for the derivation.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "camera/camera.h"
#include "camera/se3.h"

namespace evflow {

class ExposureTrajectory {
 public:
  static constexpr int kKnots = 9;  // Bézier degree 8
  static constexpr int kDof = 6;    // per knot: (rho, phi)
  static constexpr size_t kSize = size_t(kKnots) * kDof;
  static constexpr double kDefaultInitSigma = 1e-5;  // exact zeros give NaNs in some Log maps

  // Knots drawn i.i.d. N(0, init_sigma^2) from `seed` (deterministic on every platform);
  // init_sigma = 0 gives exact zeros (T(u) = identity).
  explicit ExposureTrajectory(const Camera& view = Camera{}, uint64_t seed = 0, double init_sigma = kDefaultInitSigma);

  const Camera& view() const { return view_; }

  // Flat knot storage: knot j, component c at data()[j * 6 + c]; c = 0..2 translation, 3..5 rotation.
  double* data() { return knots_.data(); }
  const double* data() const { return knots_.data(); }
  static constexpr size_t size() { return kSize; }
  lie::Vec6 knot(int j) const;
  void set_knot(int j, const lie::Vec6& xi);
  // Conversions for a float GPU buffer of 54 values (same layout).
  void copy_to(float* dst) const;
  void copy_from(const float* src);

  // Bernstein weight B_j(u) (exact 0 / 1 at the ends) and all nine at once.
  static double bernstein(int j, double u);
  static std::array<double, kKnots> bernstein_weights(double u);
  // 2n + 1 uniform times in [0, 1]: i / (2n), i = 0..2n (n = 3: 7 virtual poses). n = 0 gives {0.5}.
  static std::vector<double> virtual_times(int n = 3);

  // T(u), the offset applied on the right of the view's camera-to-world.
  lie::SE3 offset(double u) const;
  // The view's camera-to-world and the virtual one c2w_view * T(u).
  lie::SE3 view_c2w() const;
  lie::SE3 c2w_at(double u) const;
  // The virtual camera at u: same intrinsics, image size and clip planes as the view.
  Camera camera_at(double u) const;
  std::vector<Camera> virtual_cameras(int n = 3) const;

  // Adds dL/d knots (54 values, layout of data()) for the virtual camera at u whose pose
  // gradient (Rasterizer::pose_gradient(), the Camera::perturbed convention) is g.
  void accumulate_gradient(double u, const lie::Vec6& g, double* grad) const;
  // The same, returned instead of accumulated.
  std::array<double, kSize> backward(double u, const lie::Vec6& g) const;
  // Sum of the contributions of several virtual poses (us[i] with pose gradient gs[i]).
  std::array<double, kSize> backward(const std::vector<double>& us, const std::vector<lie::Vec6>& gs) const;

 private:
  Camera view_;
  std::array<double, kSize> knots_{};
};

// c2w of a camera (inverse of its world_to_camera) and the camera with a given c2w.
lie::SE3 camera_to_world(const Camera& cam);
Camera with_camera_to_world(const Camera& cam, const lie::SE3& c2w);

}  // namespace evflow
