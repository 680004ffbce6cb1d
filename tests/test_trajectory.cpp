// engine/camera: SO(3)/SE(3) maps and the Bézier exposure trajectory with its knot gradients.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "camera/se3.h"
#include "camera/trajectory.h"
#include "io/dataset.h"
#include "train/camera_model.h"
#include "train/train_config.h"

using namespace evflow;
using namespace evflow::lie;

namespace {

constexpr double kPi = std::numbers::pi;

double norm3(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

Vec3 random_axis(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 a{n(rng), n(rng), n(rng)};
  const double l = norm3(a);
  return {a[0] / l, a[1] / l, a[2] / l};
}

double max_abs_diff(const double* a, const double* b, int n) {
  double m = 0;
  for (int i = 0; i < n; ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}

// Independent rotation: from the unit quaternion (cos th/2, sin th/2 axis).
Mat3 quat_rotation(const Vec3& axis, double th) {
  const double w = std::cos(0.5 * th), s = std::sin(0.5 * th);
  const double x = s * axis[0], y = s * axis[1], z = s * axis[2];
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

// Five-point central difference.
double fd5(const std::function<double(double)>& f, double h) {
  return (8 * (f(h) - f(-h)) - (f(2 * h) - f(-2 * h))) / (12 * h);
}

// Per-component relative errors (denominator |ref| with a tiny floor relative to the largest
// component, so that exact zeros compare as 0).
std::vector<double> relative_errors(const double* a, const double* ref, int n) {
  double scale = 0;
  for (int i = 0; i < n; ++i) scale = std::max(scale, std::abs(ref[i]));
  std::vector<double> e(n);
  for (int i = 0; i < n; ++i) e[i] = std::abs(a[i] - ref[i]) / (std::abs(ref[i]) + 1e-12 * scale + 1e-300);
  return e;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A fixed random linear functional of a camera's world_to_camera (R, t).
struct LinearFunctional {
  std::array<double, 9> wR;
  std::array<double, 3> wt;
  explicit LinearFunctional(std::mt19937_64& rng) {
    std::normal_distribution<double> n(0.0, 1.0);
    for (double& w : wR) w = n(rng);
    for (double& w : wt) w = n(rng);
  }
  double operator()(const Camera& c) const {
    double s = 0;
    for (int i = 0; i < 9; ++i) s += wR[i] * c.R[i];
    for (int i = 0; i < 3; ++i) s += wt[i] * c.t[i];
    return s;
  }
  // What the rasterizer would return: dL/d delta at 0 for c.perturbed(delta), by FD in double.
  Vec6 pose_gradient(const Camera& c) const {
    Vec6 g;
    for (int k = 0; k < 6; ++k)
      g[k] = fd5(
          [&](double h) {
            std::array<double, 6> d{};
            d[k] = h;
            return (*this)(c.perturbed(d));
          },
          1e-3);
    return g;
  }
};

Camera test_view() {
  Camera c = Camera::look_at(64, 48, 50.0, {1.5, -0.7, 3.2}, {0.1, 0.2, -0.3}, {0.2, 1, 0.1});
  return c;
}

// Random knots with magnitudes log-uniform in [1e-3, max_norm] (each knot, random direction).
void randomize_knots(ExposureTrajectory& traj, std::mt19937_64& rng, double max_norm = 0.3) {
  std::uniform_real_distribution<double> lg(std::log(1e-3), std::log(max_norm));
  std::normal_distribution<double> n(0.0, 1.0);
  for (int j = 0; j < ExposureTrajectory::kKnots; ++j) {
    Vec6 x;
    double l = 0;
    for (double& v : x) {
      v = n(rng);
      l += v * v;
    }
    const double m = std::exp(lg(rng)) / std::sqrt(l);
    for (double& v : x) v *= m;
    traj.set_knot(j, x);
  }
}

// FD of f(trajectory) w.r.t. every knot component. Exp(B_j xi_j) depends on B_j xi_j only, so
// the step on knot j is h / B_j (same change of the product): accurate even for tiny B_j.
std::array<double, ExposureTrajectory::kSize> knot_fd(const ExposureTrajectory& traj, const std::vector<double>& us,
                                                      const std::function<double(const ExposureTrajectory&)>& f) {
  std::array<double, ExposureTrajectory::kSize> out{};
  for (int j = 0; j < ExposureTrajectory::kKnots; ++j) {
    double bmax = 0;
    for (double u : us) bmax = std::max(bmax, ExposureTrajectory::bernstein(j, u));
    const double h = bmax > 0 ? 1e-3 / bmax : 1e-3;
    for (int c = 0; c < 6; ++c) {
      const int k = j * 6 + c;
      out[k] = fd5(
          [&](double d) {
            ExposureTrajectory t = traj;
            t.data()[k] += d;
            return f(t);
          },
          h);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("SO(3) Exp matches the quaternion rotation and Log inverts it up to pi", "[camera]") {
  std::mt19937_64 rng(11);
  const double angles[] = {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 0.1,        0.5,        0.999,
                           1.0, 1.001, 2.0,  2.5,  3.0,  kPi - 1e-3, kPi - 1e-6, kPi - 1e-9};
  double worst_exp = 0, worst_log = 0, worst_orth = 0;
  for (double th : angles)
    for (int rep = 0; rep < 8; ++rep) {
      const Vec3 a = random_axis(rng);
      const Vec3 phi{th * a[0], th * a[1], th * a[2]};
      const Mat3 R = so3_exp(phi);
      const Mat3 Rq = quat_rotation(a, th);
      worst_exp = std::max(worst_exp, max_abs_diff(R.data(), Rq.data(), 9));
      const Mat3 RRt = mul(R, transpose(R));
      const Mat3 I = identity3();
      worst_orth = std::max(worst_orth, max_abs_diff(RRt.data(), I.data(), 9));
      const Vec3 back = so3_log(R);
      worst_log = std::max(worst_log, max_abs_diff(back.data(), phi.data(), 3));
    }
  std::printf("[camera] SO(3): |Exp - quat| %.2e, |R R^T - I| %.2e, |Log(Exp(phi)) - phi| %.2e\n", worst_exp,
              worst_orth, worst_log);
  CHECK(worst_exp < 1e-14);
  CHECK(worst_orth < 1e-14);
  CHECK(worst_log < 1e-12);

  // Exactly pi: the axis sign is arbitrary, the rotation must come back.
  for (int rep = 0; rep < 8; ++rep) {
    const Vec3 a = random_axis(rng);
    const Mat3 R = quat_rotation(a, kPi);
    const Vec3 phi = so3_log(R);
    CHECK(std::abs(norm3(phi) - kPi) < 1e-12);
    const Mat3 R2 = so3_exp(phi);
    CHECK(max_abs_diff(R.data(), R2.data(), 9) < 1e-14);
  }
  // Log of the identity is exactly zero.
  const Vec3 z = so3_log(identity3());
  CHECK((z[0] == 0 && z[1] == 0 && z[2] == 0));
}

TEST_CASE("SE(3) Exp/Log round trips, adjoint and Jacobians", "[camera]") {
  std::mt19937_64 rng(12);
  std::normal_distribution<double> n(0.0, 1.0);
  const double angles[] = {0.0, 1e-10, 1e-6, 1e-3, 0.2, 0.9, 1.0, 1.2, 2.2, 3.0, kPi - 1e-4, kPi - 1e-7};
  double worst_rt = 0, worst_jr = 0, worst_jl = 0, worst_inv = 0, worst_ad = 0;
  for (double th : angles)
    for (int rep = 0; rep < 4; ++rep) {
      const Vec3 a = random_axis(rng);
      const Vec6 xi{n(rng), n(rng), n(rng), th * a[0], th * a[1], th * a[2]};
      const SE3 T = se3_exp(xi);
      const Vec6 back = se3_log(T);
      worst_rt = std::max(worst_rt, max_abs_diff(back.data(), xi.data(), 6));

      // Jacobians by FD of Log(Exp(xi)^-1 Exp(xi + h e_k)) (right) and Log(Exp(xi + h e_k) Exp(xi)^-1) (left).
      if (th < 3.0) {
        const Mat6 Jr = se3_right_jacobian(xi), Jl = se3_left_jacobian(xi);
        const SE3 Ti = T.inverse();
        for (int k = 0; k < 6; ++k)
          for (int r = 0; r < 6; ++r) {
            auto step = [&](double h) {
              Vec6 x = xi;
              x[k] += h;
              return se3_exp(x);
            };
            const double fr = fd5([&](double h) { return se3_log(Ti * step(h))[r]; }, 1e-4);
            const double fl = fd5([&](double h) { return se3_log(step(h) * Ti)[r]; }, 1e-4);
            worst_jr = std::max(worst_jr, std::abs(fr - Jr[r * 6 + k]));
            worst_jl = std::max(worst_jl, std::abs(fl - Jl[r * 6 + k]));
          }
        const Mat6 P = mul(Jr, se3_right_jacobian_inv(xi)), Q = mul(Jl, se3_left_jacobian_inv(xi));
        for (int i = 0; i < 36; ++i) {
          const double id = (i % 7 == 0) ? 1.0 : 0.0;
          worst_inv = std::max({worst_inv, std::abs(P[i] - id), std::abs(Q[i] - id)});
        }
      }

      // Adjoint: T Exp(x) T^-1 = Exp(Ad(T) x); and the transposed apply matches the matrix.
      const Vec6 x{0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng), 0.3 * n(rng)};
      const Mat6 Ad = se3_adjoint(T);
      const SE3 lhs = T * se3_exp(x) * T.inverse(), rhs = se3_exp(mul(Ad, x));
      worst_ad = std::max(
          {worst_ad, max_abs_diff(lhs.R.data(), rhs.R.data(), 9), max_abs_diff(lhs.t.data(), rhs.t.data(), 3)});
      const Vec6 g1 = mul_transposed(Ad, x), g2 = se3_adjoint_transposed_apply(T, x);
      worst_ad = std::max(worst_ad, max_abs_diff(g1.data(), g2.data(), 6));
    }
  std::printf(
      "[camera] SE(3): |Log(Exp) - xi| %.2e, |J_r - FD| %.2e, |J_l - FD| %.2e, |J J^-1 - I| %.2e, adjoint %.2e\n",
      worst_rt, worst_jr, worst_jl, worst_inv, worst_ad);
  CHECK(worst_rt < 1e-12);
  CHECK(worst_jr < 1e-9);
  CHECK(worst_jl < 1e-9);
  CHECK(worst_inv < 1e-12);
  CHECK(worst_ad < 1e-12);

  // The small adjoint is d/ds Ad(Exp(s xi)) at 0.
  const Vec6 xi{0.3, -0.2, 0.5, 0.4, 0.1, -0.7};
  const Mat6 ad = se3_ad(xi);
  double worst = 0;
  for (int i = 0; i < 36; ++i) {
    const double f = fd5(
        [&](double s) {
          Vec6 y;
          for (int k = 0; k < 6; ++k) y[k] = s * xi[k];
          return se3_adjoint(se3_exp(y))[i];
        },
        1e-3);
    worst = std::max(worst, std::abs(f - ad[i]));
  }
  CHECK(worst < 1e-10);
}

TEST_CASE("Exposure trajectory: weights, times, zero knots, init noise, Camera::perturbed convention", "[camera]") {
  // Bernstein weights: partition of unity, exact ends.
  for (double u : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0}) {
    const auto w = ExposureTrajectory::bernstein_weights(u);
    double s = 0;
    for (double x : w) s += x;
    CHECK(std::abs(s - 1.0) < 1e-15);
  }
  CHECK(ExposureTrajectory::bernstein(0, 0.0) == 1.0);
  CHECK(ExposureTrajectory::bernstein(8, 1.0) == 1.0);
  CHECK(ExposureTrajectory::bernstein(3, 0.0) == 0.0);
  CHECK(ExposureTrajectory::bernstein(4, 0.5) == Approx(70.0 / 256.0).epsilon(1e-15));

  const auto times = ExposureTrajectory::virtual_times(3);
  REQUIRE(times.size() == 7);
  CHECK(times.front() == 0.0);
  CHECK(times[3] == 0.5);
  CHECK(times.back() == 1.0);
  CHECK(ExposureTrajectory::virtual_times(0) == std::vector<double>{0.5});
  CHECK_THROWS(ExposureTrajectory::virtual_times(-1));

  const Camera view = test_view();
  ExposureTrajectory zero(view, 0, 0.0);
  for (int i = 0; i < 54; ++i) CHECK(zero.data()[i] == 0.0);
  for (double u : times) {
    const SE3 T = zero.offset(u);
    const Mat3 I = identity3();
    CHECK(max_abs_diff(T.R.data(), I.data(), 9) == 0.0);
    CHECK(norm3(T.t) == 0.0);
  }
  const Camera mid = zero.camera_at(0.5);
  CHECK(max_abs_diff(mid.R.data(), view.R.data(), 9) < 1e-12);
  CHECK(max_abs_diff(mid.t.data(), view.t.data(), 3) < 1e-12);
  CHECK(mid.width == view.width);
  CHECK(mid.height == view.height);
  CHECK(mid.fx == view.fx);
  CHECK(mid.cy == view.cy);
  CHECK(zero.virtual_cameras(3).size() == 7);

  // Noise init: deterministic per seed, ~N(0, 1e-5), different seeds differ.
  ExposureTrajectory a(view, 7), b(view, 7), c(view, 8);
  CHECK(std::equal(a.data(), a.data() + 54, b.data()));
  CHECK(!std::equal(a.data(), a.data() + 54, c.data()));
  double ss = 0, mx = 0;
  for (int i = 0; i < 54; ++i) {
    ss += a.data()[i] * a.data()[i];
    mx = std::max(mx, std::abs(a.data()[i]));
  }
  const double sd = std::sqrt(ss / 54);
  CHECK(sd > 0.5e-5);
  CHECK(sd < 2e-5);
  CHECK(mx < 6e-5);
  const Camera noisy = a.camera_at(0.5);
  CHECK(max_abs_diff(noisy.R.data(), view.R.data(), 9) < 1e-3);

  // Float round trip for a GPU buffer.
  float f[54];
  a.copy_to(f);
  ExposureTrajectory a2(view, 0, 0.0);
  a2.copy_from(f);
  CHECK(max_abs_diff(a.data(), a2.data(), 54) < 1e-12);

  // All knots equal: the factors commute, T(u) = Exp(sum_j B_j xi) = Exp(xi) for every u, so the
  // virtual camera is Camera::perturbed(xi) (the right-multiplied convention of the rasterizer).
  const Vec6 xi{0.05, -0.02, 0.03, 0.1, -0.2, 0.15};
  ExposureTrajectory same(view, 0, 0.0);
  for (int j = 0; j < 9; ++j) same.set_knot(j, xi);
  const Camera ref = view.perturbed(xi);
  for (double u : {0.0, 0.3, 0.5, 1.0}) {
    const Camera cu = same.camera_at(u);
    CHECK(max_abs_diff(cu.R.data(), ref.R.data(), 9) < 1e-13);
    CHECK(max_abs_diff(cu.t.data(), ref.t.data(), 3) < 1e-13);
    // c2w_at and camera_at agree.
    const Camera cw = with_camera_to_world(view, same.c2w_at(u));
    CHECK(max_abs_diff(cw.R.data(), cu.R.data(), 9) < 1e-13);
    CHECK(max_abs_diff(cw.t.data(), cu.t.data(), 3) < 1e-13);
  }
  // At u = 0 only knot 0 acts, at u = 1 only knot 8.
  ExposureTrajectory ends(view, 0, 0.0);
  ends.set_knot(0, xi);
  ends.set_knot(8, {-xi[0], xi[1], xi[2], xi[3], -xi[4], xi[5]});
  const Camera c0 = ends.camera_at(0.0), r0 = view.perturbed(xi);
  CHECK(max_abs_diff(c0.R.data(), r0.R.data(), 9) < 1e-13);
  CHECK(max_abs_diff(c0.t.data(), r0.t.data(), 3) < 1e-13);
  CHECK_THROWS(ends.camera_at(1.5));
  CHECK_THROWS(ends.knot(9));
}

TEST_CASE("Exposure trajectory: knot gradients match finite differences", "[camera]") {
  std::mt19937_64 rng(2024);
  const Camera view = test_view();
  std::vector<double> all_err;
  double worst = 0;
  int cases = 0;
  // Trials 0-2: knot magnitudes 1e-3 .. 0.3; trial 3: up to 3 (angles past the series branch).
  for (int trial = 0; trial < 4; ++trial) {
    ExposureTrajectory traj(view, 100 + trial);
    randomize_knots(traj, rng, trial < 3 ? 0.3 : 3.0);
    for (double u : {0.0, 0.13, 0.5, 0.77, 1.0}) {
      const LinearFunctional L(rng);
      const Vec6 g = L.pose_gradient(traj.camera_at(u));
      const auto grad = traj.backward(u, g);
      const auto fd = knot_fd(traj, {u}, [&](const ExposureTrajectory& t) { return L(t.camera_at(u)); });
      const auto e = relative_errors(grad.data(), fd.data(), 54);
      all_err.insert(all_err.end(), e.begin(), e.end());
      worst = std::max(worst, *std::max_element(e.begin(), e.end()));
      ++cases;
      // Knots with zero weight get exactly zero gradient.
      for (int j = 0; j < 9; ++j)
        if (ExposureTrajectory::bernstein(j, u) == 0.0)
          for (int c = 0; c < 6; ++c) CHECK(grad[j * 6 + c] == 0.0);
    }
  }
  // Default initialisation (1e-5 noise): the near-zero-angle branches.
  {
    ExposureTrajectory traj(view, 5);
    const double u = 0.4;
    const LinearFunctional L(rng);
    const Vec6 g = L.pose_gradient(traj.camera_at(u));
    const auto grad = traj.backward(u, g);
    const auto fd = knot_fd(traj, {u}, [&](const ExposureTrajectory& t) { return L(t.camera_at(u)); });
    const auto e = relative_errors(grad.data(), fd.data(), 54);
    all_err.insert(all_err.end(), e.begin(), e.end());
    worst = std::max(worst, *std::max_element(e.begin(), e.end()));
    ++cases;
  }
  const double med = median(all_err);
  std::printf("[camera] knot gradient vs FD, %d (trajectory, u) cases x 54: median rel err %.2e, max %.2e\n", cases,
              med, worst);
  CHECK(med < 1e-6);
  CHECK(worst < 1e-8);

  // Summed over the 7 virtual poses, a different functional per pose.
  std::vector<double> sum_err;
  double sum_worst = 0;
  for (int trial = 0; trial < 2; ++trial) {
    ExposureTrajectory traj(view, 300 + trial);
    randomize_knots(traj, rng);
    const auto us = ExposureTrajectory::virtual_times(3);
    std::vector<LinearFunctional> Ls;
    std::vector<Vec6> gs;
    for (double u : us) {
      Ls.emplace_back(rng);
      gs.push_back(Ls.back().pose_gradient(traj.camera_at(u)));
    }
    const auto grad = traj.backward(us, gs);
    // accumulate_gradient gives the same sum
    std::array<double, 54> acc{};
    for (size_t i = 0; i < us.size(); ++i) traj.accumulate_gradient(us[i], gs[i], acc.data());
    CHECK(max_abs_diff(acc.data(), grad.data(), 54) == 0.0);
    const auto fd = knot_fd(traj, us, [&](const ExposureTrajectory& t) {
      double s = 0;
      for (size_t i = 0; i < us.size(); ++i) s += Ls[i](t.camera_at(us[i]));
      return s;
    });
    const auto e = relative_errors(grad.data(), fd.data(), 54);
    sum_err.insert(sum_err.end(), e.begin(), e.end());
    sum_worst = std::max(sum_worst, *std::max_element(e.begin(), e.end()));
  }
  const double sum_med = median(sum_err);
  std::printf("[camera] summed gradient over 7 virtual poses vs FD: median rel err %.2e, max %.2e\n", sum_med,
              sum_worst);
  CHECK(sum_med < 1e-6);
  CHECK(sum_worst < 1e-8);
  CHECK_THROWS(ExposureTrajectory(view).backward(std::vector<double>{0.5}, std::vector<Vec6>{}));
}

TEST_CASE("trajectory: the trajectory_init_sigma key sets every view's starting spread of the knots",
          "[camera][train]") {
  io::Dataset data;
  for (const double z : {-3.0, -2.0, -1.0})
    data.train.push_back({"", {}, Camera::look_at(64, 48, 60, {0, 0, z}, {0, 0, 0})});
  auto knot_rms = [&](const std::string& sigma) {
    TrainConfig cfg;
    cfg.set("mode", "blur");
    if (!sigma.empty()) cfg.set("trajectory_init_sigma", sigma);
    const CameraModel model(data, cfg);
    REQUIRE(model.trajectories().size() == data.train.size());
    double sum = 0;
    for (const ExposureTrajectory& t : model.trajectories())
      for (size_t i = 0; i < t.size(); ++i) sum += t.data()[i] * t.data()[i];
    return std::sqrt(sum / double(data.train.size() * ExposureTrajectory::size()));
  };
  // 162 draws of N(0, sigma^2): their RMS lies within 20 % of sigma (about 3.6 standard errors).
  CHECK(knot_rms("") == Approx(ExposureTrajectory::kDefaultInitSigma).epsilon(0.2));
  CHECK(knot_rms("0.01") == Approx(0.01).epsilon(0.2));
  CHECK(knot_rms("0") == 0.0);
}
