#include "camera/similarity.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace evflow {

namespace {

using lie::Mat3;
using lie::mul;
using lie::transpose;

double det(const Mat3& a) {
  return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}
Vec3 column(const Mat3& a, int c) { return {a[c], a[3 + c], a[6 + c]}; }
void set_column(Mat3& a, int c, const Vec3& v) {
  for (int r = 0; r < 3; ++r) a[r * 3 + c] = v[r];
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 normalised(const Vec3& v) {
  const double n = std::sqrt(dot(v, v));
  return {v[0] / n, v[1] / n, v[2] / n};
}
// A unit vector orthogonal to the unit vector u.
Vec3 orthogonal_to(const Vec3& u) {
  const Vec3 axis = std::fabs(u[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  return normalised(cross(u, axis));
}

// One Jacobi rotation making columns p and q of B orthogonal, applied to V too; returns false
// when they already are.
bool orthogonalise(Mat3& B, Mat3& V, int p, int q) {
  const Vec3 bp = column(B, p), bq = column(B, q);
  const double alpha = dot(bp, bp), beta = dot(bq, bq), gamma = dot(bp, bq);
  if (std::fabs(gamma) <= 1e-15 * std::sqrt(alpha * beta) || gamma == 0) return false;
  const double zeta = (beta - alpha) / (2 * gamma);
  const double t = (zeta >= 0 ? 1.0 : -1.0) / (std::fabs(zeta) + std::sqrt(1 + zeta * zeta));
  const double c = 1 / std::sqrt(1 + t * t), s = c * t;
  for (Mat3* m : {&B, &V})
    for (int r = 0; r < 3; ++r) {
      const double x = (*m)[r * 3 + p], y = (*m)[r * 3 + q];
      (*m)[r * 3 + p] = c * x - s * y;
      (*m)[r * 3 + q] = s * x + c * y;
    }
  return true;
}

}  // namespace

Vec3 Similarity::apply(const Vec3& x) const {
  Vec3 y;
  for (int r = 0; r < 3; ++r) y[r] = scale * (R[r * 3] * x[0] + R[r * 3 + 1] * x[1] + R[r * 3 + 2] * x[2]) + t[r];
  return y;
}

void svd3(const Mat3& A, Mat3& U, Vec3& sv, Mat3& V) {
  Mat3 B = A;
  V = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int sweep = 0; sweep < 60; ++sweep) {
    bool rotated = false;
    for (auto [p, q] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) rotated |= orthogonalise(B, V, p, q);
    if (!rotated) break;
  }
  int order[3] = {0, 1, 2};
  Vec3 norm;
  for (int c = 0; c < 3; ++c) norm[c] = std::sqrt(dot(column(B, c), column(B, c)));
  std::sort(order, order + 3, [&](int a, int b) { return norm[a] > norm[b]; });
  Mat3 Vs{};
  const double tiny = 1e-12 * std::max(norm[order[0]], 1e-300);
  for (int k = 0; k < 3; ++k) {
    const int c = order[k];
    sv[k] = norm[c];
    set_column(Vs, k, column(V, c));
    const Vec3 b = column(B, c);
    if (sv[k] > tiny)
      set_column(U, k, {b[0] / sv[k], b[1] / sv[k], b[2] / sv[k]});
    else if (k == 0)
      set_column(U, k, {1, 0, 0});
    else if (k == 1)
      set_column(U, k, orthogonal_to(column(U, 0)));
    else
      set_column(U, k, cross(column(U, 0), column(U, 1)));
  }
  V = Vs;
}

Similarity umeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst) {
  if (src.size() != dst.size()) throw std::invalid_argument("umeyama: the point sets differ in size");
  if (src.size() < 3) throw std::invalid_argument("umeyama: needs at least 3 point pairs");
  const double n = double(src.size());
  Vec3 mx{}, my{};
  for (size_t i = 0; i < src.size(); ++i)
    for (int r = 0; r < 3; ++r) {
      mx[r] += src[i][r] / n;
      my[r] += dst[i][r] / n;
    }
  Mat3 cov{};
  double var_x = 0;
  for (size_t i = 0; i < src.size(); ++i) {
    const Vec3 x{src[i][0] - mx[0], src[i][1] - mx[1], src[i][2] - mx[2]};
    const Vec3 y{dst[i][0] - my[0], dst[i][1] - my[1], dst[i][2] - my[2]};
    var_x += dot(x, x) / n;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) cov[r * 3 + c] += y[r] * x[c] / n;
  }
  if (!(var_x > 0)) throw std::invalid_argument("umeyama: the source points are all equal");
  Mat3 U, V;
  Vec3 d;
  svd3(cov, U, d, V);
  const double sign = det(U) * det(V) < 0 ? -1.0 : 1.0;
  const Mat3 S{1, 0, 0, 0, 1, 0, 0, 0, sign};
  Similarity sim;
  sim.R = mul(mul(U, S), transpose(V));
  sim.scale = (d[0] + d[1] + sign * d[2]) / var_x;
  const Vec3 rm = Similarity{sim.scale, sim.R, {0, 0, 0}}.apply(mx);
  for (int r = 0; r < 3; ++r) sim.t[r] = my[r] - rm[r];
  return sim;
}

double camera_extent(const std::vector<Camera>& cameras) {
  double e = 1e-12;
  for (size_t i = 0; i < cameras.size(); ++i)
    for (size_t j = i + 1; j < cameras.size(); ++j) {
      const Vec3 a = cameras[i].center(), b = cameras[j].center();
      const Vec3 d{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
      e = std::max(e, std::sqrt(dot(d, d)));
    }
  return e;
}

PoseErrors pose_errors(const std::vector<Camera>& estimated, const std::vector<Camera>& reference, double extent) {
  if (estimated.size() != reference.size()) throw std::invalid_argument("pose_errors: the camera sets differ in size");
  std::vector<Vec3> src, dst;
  for (size_t i = 0; i < estimated.size(); ++i) {
    src.push_back(estimated[i].center());
    dst.push_back(reference[i].center());
  }
  // Centres alone leave the rotation about a line of cameras loosely fixed (an arc of cameras is
  // nearly a line): add a point one extent ahead of each camera on its optical axis, in the
  // estimated frame at the scale the centres give.
  const double centres_scale = umeyama(src, dst).scale;
  const double ahead = centres_scale > 0 ? extent / centres_scale : extent;
  std::vector<Vec3> src2 = src, dst2 = dst;
  for (size_t i = 0; i < estimated.size(); ++i) {
    const auto& Re = estimated[i].R;
    const auto& Rr = reference[i].R;
    src2.push_back({src[i][0] + ahead * Re[6], src[i][1] + ahead * Re[7], src[i][2] + ahead * Re[8]});
    dst2.push_back({dst[i][0] + extent * Rr[6], dst[i][1] + extent * Rr[7], dst[i][2] + extent * Rr[8]});
  }
  PoseErrors e;
  e.alignment = umeyama(src2, dst2);
  for (size_t i = 0; i < estimated.size(); ++i) {
    // R_ref * (R_align * R_est^T): the identity for a perfect estimate.
    const Mat3 err = mul(reference[i].R, mul(e.alignment.R, transpose(estimated[i].R)));
    const Vec3 w = lie::so3_log(err);
    const double rot = std::sqrt(dot(w, w)) * 180.0 / M_PI;
    const Vec3 a = e.alignment.apply(src[i]);
    const Vec3 d{a[0] - dst[i][0], a[1] - dst[i][1], a[2] - dst[i][2]};
    const double trans = 100.0 * std::sqrt(dot(d, d)) / extent;
    e.rot_deg.push_back(rot);
    e.trans_pct.push_back(trans);
    e.rot_mean_deg += rot / double(estimated.size());
    e.trans_mean_pct += trans / double(estimated.size());
    e.rot_max_deg = std::max(e.rot_max_deg, rot);
    e.trans_max_pct = std::max(e.trans_max_pct, trans);
  }
  double pairs = 0;
  for (size_t i = 0; i < estimated.size(); ++i)
    for (size_t j = i + 1; j < estimated.size(); ++j) {
      const Mat3 rel_est = mul(estimated[i].R, transpose(estimated[j].R));
      const Mat3 rel_ref = mul(reference[i].R, transpose(reference[j].R));
      const Vec3 w = lie::so3_log(mul(rel_est, transpose(rel_ref)));
      e.relative_rot_mean_deg += std::sqrt(dot(w, w)) * 180.0 / M_PI;
      pairs += 1;
    }
  if (pairs > 0) e.relative_rot_mean_deg /= pairs;
  return e;
}

}  // namespace evflow
