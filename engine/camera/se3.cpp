#include "camera/se3.h"

#include <algorithm>
#include <cmath>

namespace evflow::lie {

namespace {

// Below this angle the closed forms of the Exp / Jacobian coefficients are replaced by their
// Taylor series. The worst closed form, (2th - 3 sin + th cos) / (2 th^5), loses about
// 120 eps / th^4 relative: 1e-14 at 1 rad. Twelve series terms are exact to rounding below 1.
constexpr double kSeriesAngle = 1.0;
constexpr int kSeriesTerms = 12;

// sum_k (-1)^k th^(2k) / (2k + n)!
double alt_factorial_series(double th2, int n) {
  double fact = 1;
  for (int i = 2; i <= n; ++i) fact *= i;
  double term = 1.0 / fact, sum = 0;
  for (int k = 0; k < kSeriesTerms; ++k) {
    sum += term;
    term *= -th2 / double((2 * k + n + 1) * (2 * k + n + 2));
  }
  return sum;
}

struct ExpCoeffs {
  double A;  // sin th / th
  double B;  // (1 - cos th) / th^2
  double C;  // (th - sin th) / th^3
};

ExpCoeffs exp_coeffs(double th2) {
  const double th = std::sqrt(th2);
  if (th < kSeriesAngle)
    return {alt_factorial_series(th2, 1), alt_factorial_series(th2, 2), alt_factorial_series(th2, 3)};
  const double s = std::sin(th), c = std::cos(th);
  return {s / th, (1 - c) / th2, (th - s) / (th2 * th)};
}

// D = (1 - (th/2) cot(th/2)) / th^2, the phi^^2 coefficient of the inverse SO(3) Jacobians.
double inv_jacobian_coeff(double th2) {
  const double th = std::sqrt(th2);
  if (th < 0.3) {
    // -sum_{n>=1} (-1)^n B_2n th^(2n-2) / (2n)!  (Bernoulli numbers)
    return 1.0 / 12 +
           th2 * (1.0 / 720 + th2 * (1.0 / 30240 +
                                     th2 * (1.0 / 1209600 + th2 * (1.0 / 47900160 + th2 * (691.0 / 1307674368000.0)))));
  }
  const double h = 0.5 * th;
  return (1 - h / std::tan(h)) / th2;
}

Mat3 scale(const Mat3& a, double s) {
  Mat3 r;
  for (int i = 0; i < 9; ++i) r[i] = a[i] * s;
  return r;
}
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// I + a K + b K^2 for K = phi^ (K^2 = phi phi^T - th^2 I).
Mat3 poly_in_hat(const Vec3& phi, double a, double b) {
  const double th2 = dot(phi, phi);
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i * 3 + j] = (i == j ? 1.0 - b * th2 : 0.0) + b * phi[i] * phi[j];
  const Mat3 K = hat(phi);
  for (int i = 0; i < 9; ++i) r[i] += a * K[i];
  return r;
}

void set_block(Mat6& m, int bi, int bj, const Mat3& b) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[(bi * 3 + i) * 6 + bj * 3 + j] = b[i * 3 + j];
}

Vec3 head(const Vec6& v) { return {v[0], v[1], v[2]}; }
Vec3 tail(const Vec6& v) { return {v[3], v[4], v[5]}; }

}  // namespace

// ---- small helpers -------------------------------------------------------------------------
Mat3 identity3() { return {1, 0, 0, 0, 1, 0, 0, 0, 1}; }

Mat3 hat(const Vec3& v) { return {0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0}; }

Vec3 vee(const Mat3& m) { return {0.5 * (m[7] - m[5]), 0.5 * (m[2] - m[6]), 0.5 * (m[3] - m[1])}; }

Mat3 mul(const Mat3& a, const Mat3& b) {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
  return r;
}

Vec3 mul(const Mat3& a, const Vec3& v) {
  return {a[0] * v[0] + a[1] * v[1] + a[2] * v[2], a[3] * v[0] + a[4] * v[1] + a[5] * v[2],
          a[6] * v[0] + a[7] * v[1] + a[8] * v[2]};
}

Mat3 transpose(const Mat3& a) { return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]}; }

Vec6 mul(const Mat6& a, const Vec6& v) {
  Vec6 r{};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r[i] += a[i * 6 + j] * v[j];
  return r;
}

Vec6 mul_transposed(const Mat6& a, const Vec6& v) {
  Vec6 r{};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r[j] += a[i * 6 + j] * v[i];
  return r;
}

Mat6 mul(const Mat6& a, const Mat6& b) {
  Mat6 r{};
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 6; ++k)
      for (int j = 0; j < 6; ++j) r[i * 6 + j] += a[i * 6 + k] * b[k * 6 + j];
  return r;
}

Mat6 transpose(const Mat6& a) {
  Mat6 r;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r[j * 6 + i] = a[i * 6 + j];
  return r;
}

// ---- SO(3) ---------------------------------------------------------------------------------
Mat3 so3_exp(const Vec3& phi) {
  const ExpCoeffs k = exp_coeffs(dot(phi, phi));
  return poly_in_hat(phi, k.A, k.B);
}

Vec3 so3_log(const Mat3& R) {
  const Vec3 v = vee(R);  // sin(th) * axis
  const double s = std::sqrt(dot(v, v));
  const double c = std::clamp(0.5 * (R[0] + R[4] + R[8] - 1.0), -1.0, 1.0);
  const double th = std::atan2(s, c);
  if (c > -0.5) {
    // th < 2 pi / 3: the skew part determines the axis well; th / s -> 1 as th -> 0.
    const double f = s > 0 ? th / s : 1.0;
    return {f * v[0], f * v[1], f * v[2]};
  }
  // Near pi: (R + R^T)/2 - cos(th) I = (1 - cos th) a a^T; take its largest column.
  const double one_minus_c = 1.0 - c;
  double S[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) S[i * 3 + j] = 0.5 * (R[i * 3 + j] + R[j * 3 + i]) - (i == j ? c : 0.0);
  int m = 0;
  if (S[4] > S[m * 4]) m = 1;
  if (S[8] > S[m * 4]) m = 2;
  const double n = std::sqrt(std::max(S[m * 4], 0.0) * one_minus_c);
  Vec3 a{S[m], S[3 + m], S[6 + m]};  // column m
  for (double& x : a) x /= n;
  const double an = std::sqrt(dot(a, a));
  for (double& x : a) x /= an;  // remove residual rounding of the length
  if (dot(a, v) < 0)
    for (double& x : a) x = -x;
  return {th * a[0], th * a[1], th * a[2]};
}

Mat3 so3_left_jacobian(const Vec3& phi) {
  const ExpCoeffs k = exp_coeffs(dot(phi, phi));
  return poly_in_hat(phi, k.B, k.C);
}

Mat3 so3_right_jacobian(const Vec3& phi) {
  const ExpCoeffs k = exp_coeffs(dot(phi, phi));
  return poly_in_hat(phi, -k.B, k.C);
}

Mat3 so3_left_jacobian_inv(const Vec3& phi) { return poly_in_hat(phi, -0.5, inv_jacobian_coeff(dot(phi, phi))); }

Mat3 so3_right_jacobian_inv(const Vec3& phi) { return poly_in_hat(phi, 0.5, inv_jacobian_coeff(dot(phi, phi))); }

// ---- SE(3) ---------------------------------------------------------------------------------
SE3 SE3::operator*(const SE3& o) const {
  SE3 r;
  r.R = mul(R, o.R);
  const Vec3 Rt = mul(R, o.t);
  for (int i = 0; i < 3; ++i) r.t[i] = Rt[i] + t[i];
  return r;
}

SE3 SE3::inverse() const {
  SE3 r;
  r.R = transpose(R);
  const Vec3 Rt = mul(r.R, t);
  r.t = {-Rt[0], -Rt[1], -Rt[2]};
  return r;
}

Vec3 SE3::apply(const Vec3& p) const {
  const Vec3 q = mul(R, p);
  return {q[0] + t[0], q[1] + t[1], q[2] + t[2]};
}

SE3 se3_exp(const Vec6& xi) {
  const Vec3 rho = head(xi), phi = tail(xi);
  const ExpCoeffs k = exp_coeffs(dot(phi, phi));
  SE3 T;
  T.R = poly_in_hat(phi, k.A, k.B);
  T.t = mul(poly_in_hat(phi, k.B, k.C), rho);  // V = J_l(phi)
  return T;
}

Vec6 se3_log(const SE3& T) {
  const Vec3 phi = so3_log(T.R);
  const Vec3 rho = mul(so3_left_jacobian_inv(phi), T.t);
  return {rho[0], rho[1], rho[2], phi[0], phi[1], phi[2]};
}

Mat6 se3_adjoint(const SE3& T) {
  Mat6 m{};
  set_block(m, 0, 0, T.R);
  set_block(m, 0, 1, mul(hat(T.t), T.R));
  set_block(m, 1, 1, T.R);
  return m;
}

Vec6 se3_adjoint_transposed_apply(const SE3& T, const Vec6& g) {
  // Ad^T = [ R^T  0 ; -R^T t^  R^T ]
  const Vec3 gr = head(g), gp = tail(g);
  const Vec3 tx = cross(T.t, gr);
  const Mat3 Rt = transpose(T.R);
  const Vec3 a = mul(Rt, gr);
  const Vec3 b = mul(Rt, Vec3{gp[0] - tx[0], gp[1] - tx[1], gp[2] - tx[2]});
  return {a[0], a[1], a[2], b[0], b[1], b[2]};
}

Mat6 se3_ad(const Vec6& xi) {
  Mat6 m{};
  const Mat3 P = hat(tail(xi));
  set_block(m, 0, 0, P);
  set_block(m, 0, 1, hat(head(xi)));
  set_block(m, 1, 1, P);
  return m;
}

Mat3 se3_q_block(const Vec3& rho, const Vec3& phi) {
  // Q = 1/2 r^ + c1 (p^r^ + r^p^ + p^r^p^) + c2 (p^p^r^ + r^p^p^ - 3 p^r^p^)
  //     + c3 (p^r^p^p^ + p^p^r^p^)      [Barfoot, State Estimation for Robotics, (7.86)]
  // c1 = (th - sin)/th^3, c2 = (th^2 + 2 cos - 2)/(2 th^4), c3 = (2 th - 3 sin + th cos)/(2 th^5)
  const double th2 = dot(phi, phi), th = std::sqrt(th2);
  double c1, c2, c3;
  if (th < kSeriesAngle) {
    c1 = alt_factorial_series(th2, 3);
    c2 = alt_factorial_series(th2, 4);
    // sum_k (-1)^k (k+1) th^(2k) / (2k+5)!
    double term = 1.0 / 120, sum = 0;
    for (int k = 0; k < kSeriesTerms; ++k) {
      sum += (k + 1) * term;
      term *= -th2 / double((2 * k + 6) * (2 * k + 7));
    }
    c3 = sum;
  } else {
    const double s = std::sin(th), c = std::cos(th), th4 = th2 * th2;
    c1 = (th - s) / (th2 * th);
    c2 = (th2 + 2 * c - 2) / (2 * th4);
    c3 = (2 * th - 3 * s + th * c) / (2 * th4 * th);
  }
  const Mat3 r = hat(rho), p = hat(phi);
  const Mat3 pr = mul(p, r), rp = mul(r, p), prp = mul(pr, p), ppr = mul(p, pr), rpp = mul(rp, p);
  const Mat3 prpp = mul(prp, p), pprp = mul(p, prp);
  Mat3 Q;
  for (int i = 0; i < 9; ++i)
    Q[i] = 0.5 * r[i] + c1 * (pr[i] + rp[i] + prp[i]) + c2 * (ppr[i] + rpp[i] - 3 * prp[i]) + c3 * (prpp[i] + pprp[i]);
  return Q;
}

Mat6 se3_left_jacobian(const Vec6& xi) {
  Mat6 m{};
  const Mat3 J = so3_left_jacobian(tail(xi));
  set_block(m, 0, 0, J);
  set_block(m, 0, 1, se3_q_block(head(xi), tail(xi)));
  set_block(m, 1, 1, J);
  return m;
}

Mat6 se3_right_jacobian(const Vec6& xi) { return se3_left_jacobian({-xi[0], -xi[1], -xi[2], -xi[3], -xi[4], -xi[5]}); }

Mat6 se3_left_jacobian_inv(const Vec6& xi) {
  Mat6 m{};
  const Mat3 Ji = so3_left_jacobian_inv(tail(xi));
  const Mat3 Q = se3_q_block(head(xi), tail(xi));
  set_block(m, 0, 0, Ji);
  set_block(m, 0, 1, scale(mul(mul(Ji, Q), Ji), -1.0));
  set_block(m, 1, 1, Ji);
  return m;
}

Mat6 se3_right_jacobian_inv(const Vec6& xi) {
  return se3_left_jacobian_inv({-xi[0], -xi[1], -xi[2], -xi[3], -xi[4], -xi[5]});
}

}  // namespace evflow::lie
