#include "camera/trajectory.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace evflow {

using lie::Mat3;
using lie::SE3;
using lie::Vec3;
using lie::Vec6;

namespace {

uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Uniform in (0, 1]: never 0, so that log() below is finite.
double uniform01(uint64_t& state) { return double((splitmix64(state) >> 11) + 1) * 0x1.0p-53; }

constexpr double kBinom8[9] = {1, 8, 28, 56, 70, 56, 28, 8, 1};

double ipow(double x, int n) {
  double r = 1;
  for (int i = 0; i < n; ++i) r *= x;
  return r;
}

void check_knot_index(int j) {
  if (j < 0 || j >= ExposureTrajectory::kKnots)
    throw std::out_of_range("ExposureTrajectory: knot index " + std::to_string(j) + " outside 0..8");
}

void check_u(double u) {
  if (!(u >= 0.0 && u <= 1.0))
    throw std::invalid_argument("ExposureTrajectory: exposure time u = " + std::to_string(u) + " outside [0, 1]");
}

}  // namespace

SE3 camera_to_world(const Camera& cam) {
  SE3 w2c;
  w2c.R = cam.R;
  w2c.t = cam.t;
  return w2c.inverse();
}

Camera with_camera_to_world(const Camera& cam, const SE3& c2w) {
  const SE3 w2c = c2w.inverse();
  Camera c = cam;
  c.R = w2c.R;
  c.t = w2c.t;
  return c;
}

ExposureTrajectory::ExposureTrajectory(const Camera& view, uint64_t seed, double init_sigma) : view_(view) {
  if (!(init_sigma >= 0.0) || !std::isfinite(init_sigma))
    throw std::invalid_argument("ExposureTrajectory: init_sigma must be finite and >= 0");
  if (init_sigma == 0.0) return;
  uint64_t state = seed ^ 0x5DEECE66Dull;
  for (size_t i = 0; i < kSize; i += 2) {
    // Box-Muller: two independent normals per pair of uniforms.
    const double r = std::sqrt(-2.0 * std::log(uniform01(state)));
    const double a = 2.0 * std::numbers::pi * uniform01(state);
    knots_[i] = init_sigma * r * std::cos(a);
    if (i + 1 < kSize) knots_[i + 1] = init_sigma * r * std::sin(a);
  }
}

Vec6 ExposureTrajectory::knot(int j) const {
  check_knot_index(j);
  Vec6 xi;
  for (int c = 0; c < kDof; ++c) xi[c] = knots_[j * kDof + c];
  return xi;
}

void ExposureTrajectory::set_knot(int j, const Vec6& xi) {
  check_knot_index(j);
  for (int c = 0; c < kDof; ++c) knots_[j * kDof + c] = xi[c];
}

void ExposureTrajectory::copy_to(float* dst) const {
  for (size_t i = 0; i < kSize; ++i) dst[i] = float(knots_[i]);
}

void ExposureTrajectory::copy_from(const float* src) {
  for (size_t i = 0; i < kSize; ++i) knots_[i] = double(src[i]);
}

double ExposureTrajectory::bernstein(int j, double u) {
  check_knot_index(j);
  return kBinom8[j] * ipow(1.0 - u, 8 - j) * ipow(u, j);
}

std::array<double, ExposureTrajectory::kKnots> ExposureTrajectory::bernstein_weights(double u) {
  std::array<double, kKnots> w;
  for (int j = 0; j < kKnots; ++j) w[j] = bernstein(j, u);
  return w;
}

std::vector<double> ExposureTrajectory::virtual_times(int n) {
  if (n < 0) throw std::invalid_argument("ExposureTrajectory::virtual_times: n must be >= 0");
  if (n == 0) return {0.5};
  std::vector<double> u(2 * n + 1);
  for (int i = 0; i <= 2 * n; ++i) u[i] = double(i) / double(2 * n);
  u[2 * n] = 1.0;
  return u;
}

SE3 ExposureTrajectory::offset(double u) const {
  check_u(u);
  const auto w = bernstein_weights(u);
  SE3 T;
  for (int j = 0; j < kKnots; ++j) {
    if (w[j] == 0.0) continue;  // Exp(0) = I exactly
    Vec6 x;
    for (int c = 0; c < kDof; ++c) x[c] = w[j] * knots_[j * kDof + c];
    T = T * lie::se3_exp(x);
  }
  return T;
}

SE3 ExposureTrajectory::view_c2w() const { return camera_to_world(view_); }

SE3 ExposureTrajectory::c2w_at(double u) const { return view_c2w() * offset(u); }

Camera ExposureTrajectory::camera_at(double u) const {
  // w2c(u) = T(u)^-1 * w2c_view: R' = R_T^T R, t' = R_T^T (t - t_T). Exact for T = I.
  const SE3 T = offset(u);
  const Mat3 RtT = lie::transpose(T.R);
  Camera c = view_;
  c.R = lie::mul(RtT, view_.R);
  c.t = lie::mul(RtT, Vec3{view_.t[0] - T.t[0], view_.t[1] - T.t[1], view_.t[2] - T.t[2]});
  return c;
}

std::vector<Camera> ExposureTrajectory::virtual_cameras(int n) const {
  std::vector<Camera> cams;
  for (double u : virtual_times(n)) cams.push_back(camera_at(u));
  return cams;
}

void ExposureTrajectory::accumulate_gradient(double u, const Vec6& g, double* grad) const {
  check_u(u);
  // T = E_0 ... E_8, E_j = Exp(b_j xi_j). Perturbing xi_j by e:
  //   E_j -> E_j Exp(b_j J_r(b_j xi_j) e), and moving that factor past S_j = E_{j+1} ... E_8:
  //   T -> T Exp(Ad(S_j^-1) b_j J_r(b_j xi_j) e), so dL/d xi_j = b_j J_r^T Ad(S_j^-1)^T g.
  // h carries Ad(S_j^-1)^T g, updated right to left by h <- Ad(E_j^-1)^T h.
  const auto w = bernstein_weights(u);
  Vec6 h = g;
  for (int j = kKnots - 1; j >= 0; --j) {
    if (w[j] == 0.0) continue;  // no contribution, and E_j = I leaves h unchanged
    Vec6 x;
    for (int c = 0; c < kDof; ++c) x[c] = w[j] * knots_[j * kDof + c];
    const Vec6 gj = lie::mul_transposed(lie::se3_right_jacobian(x), h);
    for (int c = 0; c < kDof; ++c) grad[j * kDof + c] += w[j] * gj[c];
    if (j > 0) h = lie::se3_adjoint_transposed_apply(lie::se3_exp(x).inverse(), h);
  }
}

std::array<double, ExposureTrajectory::kSize> ExposureTrajectory::backward(double u, const Vec6& g) const {
  std::array<double, kSize> grad{};
  accumulate_gradient(u, g, grad.data());
  return grad;
}

std::array<double, ExposureTrajectory::kSize> ExposureTrajectory::backward(const std::vector<double>& us,
                                                                           const std::vector<Vec6>& gs) const {
  if (us.size() != gs.size())
    throw std::invalid_argument("ExposureTrajectory::backward: " + std::to_string(us.size()) + " times but " +
                                std::to_string(gs.size()) + " pose gradients");
  std::array<double, kSize> grad{};
  for (size_t i = 0; i < us.size(); ++i) accumulate_gradient(us[i], gs[i], grad.data());
  return grad;
}

}  // namespace evflow
