#include "camera/camera.h"

#include <cmath>

namespace evflow {

std::array<double, 3> Camera::center() const {
  return {-(R[0] * t[0] + R[3] * t[1] + R[6] * t[2]), -(R[1] * t[0] + R[4] * t[1] + R[7] * t[2]),
          -(R[2] * t[0] + R[5] * t[1] + R[8] * t[2])};
}

// SE(3) exponential of (rho, phi): rotation by Rodrigues, translation V * rho.
static void se3_exp(const std::array<double, 6>& d, double Rm[9], double tv[3]) {
  const double px = d[3], py = d[4], pz = d[5];
  const double th2 = px * px + py * py + pz * pz, th = std::sqrt(th2);
  double A, B, C;  // sin/th, (1-cos)/th^2, (th - sin)/th^3
  if (th < 1e-6) {
    A = 1 - th2 / 6;
    B = 0.5 - th2 / 24;
    C = 1.0 / 6 - th2 / 120;
  } else {
    A = std::sin(th) / th;
    B = (1 - std::cos(th)) / th2;
    C = (th - std::sin(th)) / (th2 * th);
  }
  const double K[9] = {0, -pz, py, pz, 0, -px, -py, px, 0};
  double K2[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      K2[i * 3 + j] = 0;
      for (int k = 0; k < 3; ++k) K2[i * 3 + j] += K[i * 3 + k] * K[k * 3 + j];
    }
  double V[9];
  for (int i = 0; i < 9; ++i) {
    const double I = (i % 4 == 0) ? 1.0 : 0.0;
    Rm[i] = I + A * K[i] + B * K2[i];
    V[i] = I + B * K[i] + C * K2[i];
  }
  for (int i = 0; i < 3; ++i) tv[i] = V[i * 3] * d[0] + V[i * 3 + 1] * d[1] + V[i * 3 + 2] * d[2];
}

Camera Camera::perturbed(const std::array<double, 6>& delta) const {
  // w2c' = Exp(-delta) * w2c
  std::array<double, 6> neg;
  for (int i = 0; i < 6; ++i) neg[i] = -delta[i];
  double Re[9], te[3];
  se3_exp(neg, Re, te);
  Camera c = *this;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += Re[i * 3 + k] * R[k * 3 + j];
      c.R[i * 3 + j] = s;
    }
    c.t[i] = Re[i * 3] * t[0] + Re[i * 3 + 1] * t[1] + Re[i * 3 + 2] * t[2] + te[i];
  }
  return c;
}

Camera Camera::look_at(uint32_t width, uint32_t height, double fov_y_deg, const std::array<double, 3>& eye,
                       const std::array<double, 3>& target, const std::array<double, 3>& up) {
  auto sub = [](auto a, auto b) { return std::array<double, 3>{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto cross = [](auto a, auto b) {
    return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto norm = [](auto a) {
    double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return std::array<double, 3>{a[0] / l, a[1] / l, a[2] / l};
  };
  auto z = norm(sub(target, eye));  // forward
  auto x = norm(cross(z, up));      // right (y down in the image)
  auto y = cross(z, x);             // down
  Camera c;
  c.width = width;
  c.height = height;
  c.fy = 0.5 * height / std::tan(0.5 * fov_y_deg * M_PI / 180.0);
  c.fx = c.fy;
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  c.R = {x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1], z[2]};
  for (int i = 0; i < 3; ++i) c.t[i] = -(c.R[i * 3] * eye[0] + c.R[i * 3 + 1] * eye[1] + c.R[i * 3 + 2] * eye[2]);
  return c;
}

}  // namespace evflow
