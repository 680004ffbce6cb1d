// SO(3) / SE(3) in double precision: Exp, Log, adjoints and the left / right Jacobians of Exp.
//
// Conventions (the same as Camera::perturbed and the rasterizer's pose gradient):
//   * se(3) vectors are xi = (rho, phi): translation part first, rotation part second.
//   * Exp(xi) = [ Exp(phi)  V(phi) rho ; 0 1 ], Exp(phi) by Rodrigues.
//   * Matrices are row-major std::arrays (Mat3: 9 values, Mat6: 36 values).
//   * Adjoint: T Exp(x) T^-1 = Exp(Ad(T) x), Ad(T) = [ R  t^R ; 0  R ] (t^ = hat(t)).
//   * Jacobians of Exp: Exp(xi + d) ~ Exp(J_l(xi) d) Exp(xi) ~ Exp(xi) Exp(J_r(xi) d),
//     J_r(xi) = J_l(-xi).
// Every function is smooth through zero angle (Taylor series below 1 rad where the closed forms
// cancel) and Log is accurate up to and at an angle of pi (the axis is then taken from the
// symmetric part of R). See docs/trajectory.md.
#pragma once
#include <array>

namespace evflow::lie {

using Vec3 = std::array<double, 3>;
using Vec6 = std::array<double, 6>;
using Mat3 = std::array<double, 9>;   // row-major
using Mat6 = std::array<double, 36>;  // row-major

// ---- small 3x3 helpers ---------------------------------------------------------------------
Mat3 identity3();
Mat3 hat(const Vec3& v);  // v^ : hat(v) * w = v x w
Vec3 vee(const Mat3& m);  // inverse of hat on the skew part: ((m21 - m12), (m02 - m20), (m10 - m01)) / 2
Mat3 mul(const Mat3& a, const Mat3& b);
Vec3 mul(const Mat3& a, const Vec3& v);
Mat3 transpose(const Mat3& a);
Vec6 mul(const Mat6& a, const Vec6& v);
Vec6 mul_transposed(const Mat6& a, const Vec6& v);  // a^T v
Mat6 mul(const Mat6& a, const Mat6& b);
Mat6 transpose(const Mat6& a);

// ---- SO(3) ---------------------------------------------------------------------------------
Mat3 so3_exp(const Vec3& phi);
// Rotation vector with angle in [0, pi]. R must be a rotation (orthonormal, det +1) up to
// rounding. At exactly pi the sign of the axis is arbitrary (both are correct).
Vec3 so3_log(const Mat3& R);
Mat3 so3_left_jacobian(const Vec3& phi);       // I + (1-cos)/th^2 phi^ + (th-sin)/th^3 phi^^2
Mat3 so3_right_jacobian(const Vec3& phi);      // J_l(-phi)
Mat3 so3_left_jacobian_inv(const Vec3& phi);   // I - phi^/2 + D phi^^2
Mat3 so3_right_jacobian_inv(const Vec3& phi);  // I + phi^/2 + D phi^^2

// ---- SE(3) ---------------------------------------------------------------------------------
struct SE3 {
  Mat3 R{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 t{0, 0, 0};

  static SE3 identity() { return {}; }
  SE3 operator*(const SE3& o) const;  // composition: (this * o)(p) = this(o(p))
  SE3 inverse() const;
  Vec3 apply(const Vec3& p) const;  // R p + t
};

SE3 se3_exp(const Vec6& xi);
Vec6 se3_log(const SE3& T);  // rotation angle in [0, pi]
Mat6 se3_adjoint(const SE3& T);
// Ad(T)^T g without forming the matrix (pulls a cotangent back through an adjoint).
Vec6 se3_adjoint_transposed_apply(const SE3& T, const Vec6& g);
Mat6 se3_ad(const Vec6& xi);  // small adjoint: [ phi^ rho^ ; 0 phi^ ]
// Barfoot's Q(rho, phi): the upper-right block of the SE(3) left Jacobian.
Mat3 se3_q_block(const Vec3& rho, const Vec3& phi);
Mat6 se3_left_jacobian(const Vec6& xi);      // [ J_l(phi)  Q(rho,phi) ; 0  J_l(phi) ]
Mat6 se3_right_jacobian(const Vec6& xi);     // J_l(-xi)
Mat6 se3_left_jacobian_inv(const Vec6& xi);  // [ J^-1  -J^-1 Q J^-1 ; 0  J^-1 ]
Mat6 se3_right_jacobian_inv(const Vec6& xi);

}  // namespace evflow::lie
