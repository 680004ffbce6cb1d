// engine/camera/similarity: Umeyama's similarity fit, the 3x3 SVD under it, and pose errors
// after alignment.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "camera/se3.h"
#include "camera/similarity.h"

using namespace evflow;

namespace {

double max_abs_diff(const std::array<double, 9>& a, const std::array<double, 9>& b) {
  double m = 0;
  for (int i = 0; i < 9; ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

std::vector<Vec3> random_points(std::mt19937_64& rng, size_t n, bool planar) {
  std::normal_distribution<double> g(0, 1);
  std::vector<Vec3> p;
  for (size_t i = 0; i < n; ++i) p.push_back({g(rng), g(rng), planar ? 0.0 : g(rng)});
  return p;
}

}  // namespace

TEST_CASE("svd3 reconstructs the matrix with orthogonal factors", "[similarity]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0, 1);
  for (int trial = 0; trial < 50; ++trial) {
    std::array<double, 9> A;
    for (double& a : A) a = g(rng);
    if (trial % 5 == 0)  // rank 2: the third row a combination of the first two
      for (int c = 0; c < 3; ++c) A[6 + c] = 0.5 * A[c] - 2 * A[3 + c];
    std::array<double, 9> U, V;
    Vec3 s;
    svd3(A, U, s, V);
    REQUIRE(s[0] >= s[1]);
    REQUIRE(s[1] >= s[2]);
    REQUIRE(s[2] >= 0);
    const lie::Mat3 D{s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]};
    CHECK(max_abs_diff(lie::mul(lie::mul(U, D), lie::transpose(V)), A) < 1e-12);
    CHECK(max_abs_diff(lie::mul(lie::transpose(U), U), lie::identity3()) < 1e-12);
    CHECK(max_abs_diff(lie::mul(lie::transpose(V), V), lie::identity3()) < 1e-12);
  }
}

TEST_CASE("umeyama recovers a known similarity, also from coplanar points", "[similarity]") {
  std::mt19937_64 rng(11);
  for (bool planar : {false, true}) {
    const std::vector<Vec3> src = random_points(rng, 12, planar);
    Similarity truth;
    truth.scale = 3.7;
    truth.R = lie::so3_exp({0.3, -1.2, 2.0});
    truth.t = {1.5, -4, 0.25};
    std::vector<Vec3> dst;
    for (const Vec3& x : src) dst.push_back(truth.apply(x));
    const Similarity fit = umeyama(src, dst);
    CHECK(fit.scale == Approx(truth.scale).epsilon(1e-12));
    CHECK(max_abs_diff(fit.R, truth.R) < 1e-12);
    for (int r = 0; r < 3; ++r) CHECK(fit.t[r] == Approx(truth.t[r]).margin(1e-11));
  }
}

TEST_CASE("umeyama returns a rotation where the best orthogonal map is a reflection", "[similarity]") {
  // dst is src mirrored in z: the least-squares rotation must have det +1, not copy the mirror.
  std::mt19937_64 rng(3);
  const std::vector<Vec3> src = random_points(rng, 20, false);
  std::vector<Vec3> dst;
  for (const Vec3& x : src) dst.push_back({x[0], x[1], -x[2]});
  const Similarity fit = umeyama(src, dst);
  const auto& R = fit.R;
  const double det =
      R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
  CHECK(det == Approx(1.0).epsilon(1e-12));
  CHECK(max_abs_diff(lie::mul(lie::transpose(R), R), lie::identity3()) < 1e-12);
}

TEST_CASE("umeyama rejects too few points and points without spread", "[similarity]") {
  const std::vector<Vec3> two{{0, 0, 0}, {1, 0, 0}};
  CHECK_THROWS_WITH(umeyama(two, two), Catch::Contains("at least 3"));
  const std::vector<Vec3> same{{1, 2, 3}, {1, 2, 3}, {1, 2, 3}};
  CHECK_THROWS_WITH(umeyama(same, same), Catch::Contains("all equal"));
}

TEST_CASE("pose_errors: zero for a similar copy of the cameras, the perturbation's size otherwise", "[similarity]") {
  std::vector<Camera> ref;
  for (int i = 0; i < 8; ++i) {
    const double a = 0.15 * i;
    ref.push_back(Camera::look_at(64, 48, 50, {4 * std::sin(a), 0.3 * i, 4 * std::cos(a)}, {0, 0, 0}));
  }
  // The same rig seen in another frame: x' = s R x + t, so w2c' = [R_c R^T | s t_c - R_c R^T t].
  Similarity g;
  g.scale = 0.2;
  g.R = lie::so3_exp({1.0, 0.5, -0.7});
  g.t = {3, 1, -2};
  std::vector<Camera> est;
  for (const Camera& c : ref) {
    Camera e = c;
    e.R = lie::mul(c.R, lie::transpose(g.R));
    const Vec3 Rt = lie::mul(e.R, g.t);
    for (int r = 0; r < 3; ++r) e.t[r] = g.scale * c.t[r] - Rt[r];
    est.push_back(e);
  }
  const double extent = camera_extent(ref);
  PoseErrors e = pose_errors(est, ref, extent);
  CHECK(e.rot_max_deg < 1e-6);
  CHECK(e.trans_max_pct < 1e-9);
  CHECK(e.alignment.scale == Approx(1 / g.scale).epsilon(1e-9));
  CHECK(e.relative_rot_mean_deg < 1e-6);
  // Turn one of the 8 estimated cameras by 2 degrees: the error is about 2 degrees there (its axis
  // point pulls the alignment a little) and small elsewhere.
  est[3] = est[3].perturbed({0, 0, 0, 0, 2 * M_PI / 180, 0});
  e = pose_errors(est, ref, extent);
  CHECK(e.rot_deg[3] == Approx(2.0).margin(0.3));
  CHECK(e.rot_max_deg == e.rot_deg[3]);
  for (int i : {0, 1, 2, 4, 5, 6, 7}) CHECK(e.rot_deg[i] < 0.3);
  CHECK(e.trans_max_pct < 1.0);
  // 7 of the 28 pairs hold camera 3, each off by its 2 degrees.
  CHECK(e.relative_rot_mean_deg == Approx(2.0 * 7 / 28).epsilon(1e-6));
}
