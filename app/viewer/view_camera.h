// The viewer's orbit camera as pure functions (header-only: the tests include it to render the
// exact view `evflow view` starts with). docs/viewer.md describes the controls.
//
// World convention is OpenCV's (x right, y down, z forward for an identity camera), so world
// "up" is -y. An orbit is a target point, a distance, a yaw (about the up axis) and a pitch
// (positive = the eye above the target, looking down). yaw = pitch = 0 is the identity
// orientation: the eye at target - distance * (0, 0, 1), looking along +z.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "splat/gaussians.h"

namespace evflow::viewer {

inline constexpr double kViewFovYDeg = 60.0;
inline constexpr double kMaxPitchRad = 1.5;  // about 86 degrees: never straight up or down

struct Orbit {
  std::array<double, 3> target{0, 0, 0};
  double distance = 5.0;
  double yaw = 0.0;    // radians, about world up (-y)
  double pitch = 0.0;  // radians, clamped to +-kMaxPitchRad
  double fov_y_deg = kViewFovYDeg;
};

// Unit vector from the eye to the target.
inline std::array<double, 3> orbit_forward(const Orbit& o) {
  const double cp = std::cos(o.pitch);
  return {std::sin(o.yaw) * cp, std::sin(o.pitch), std::cos(o.yaw) * cp};
}

inline std::array<double, 3> orbit_eye(const Orbit& o) {
  auto f = orbit_forward(o);
  return {o.target[0] - o.distance * f[0], o.target[1] - o.distance * f[1], o.target[2] - o.distance * f[2]};
}

// The camera of an orbit for a width x height image (square pixels, principal point at the
// centre, vertical field of view o.fov_y_deg).
inline Camera orbit_camera(const Orbit& o, uint32_t width, uint32_t height) {
  Camera c = Camera::look_at(width, height, o.fov_y_deg, orbit_eye(o), o.target, {0.0, -1.0, 0.0});
  c.near_plane = 0.01;
  return c;
}

// The orbit the viewer starts with, from the cloud alone:
//   target   = the mean of the Gaussians' centres (the origin for an empty cloud);
//   r        = the root-mean-square distance of the centres from the target (1 if zero);
//   distance = r / tan(fov_y / 2), so a sphere of radius r about fills the image height;
//   yaw = pitch = 0 (looking along +z, the direction an identity camera looks).
inline Orbit initial_orbit(const GaussianCloud& cloud) {
  Orbit o;
  const size_t n = cloud.size();
  if (n == 0) return o;
  double s[3] = {0, 0, 0};
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) s[k] += cloud.means[i * 3 + k];
  for (int k = 0; k < 3; ++k) o.target[k] = s[k] / double(n);
  double ss = 0;
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double d = cloud.means[i * 3 + k] - o.target[k];
      ss += d * d;
    }
  double r = std::sqrt(ss / double(n));
  if (!(r > 1e-9) || !std::isfinite(r)) r = 1.0;
  o.distance = r / std::tan(0.5 * o.fov_y_deg * M_PI / 180.0);
  return o;
}

// The camera of the first frame `evflow view` shows in a width x height window.
inline Camera initial_view_camera(const GaussianCloud& cloud, uint32_t width, uint32_t height) {
  return orbit_camera(initial_orbit(cloud), width, height);
}

// An orbit whose eye is the camera's centre and which looks along the camera's viewing axis,
// with the camera's vertical field of view (roll is dropped: an orbit keeps world up up). The
// target lies `distance` ahead of the eye. `evflow train --view` starts at a training view.
inline Orbit orbit_from_camera(const Camera& cam, double distance) {
  Orbit o;
  const std::array<double, 3> f{cam.R[6], cam.R[7], cam.R[8]};  // camera z axis in world
  o.pitch = std::clamp(std::asin(std::clamp(f[1], -1.0, 1.0)), -kMaxPitchRad, kMaxPitchRad);
  o.yaw = std::atan2(f[0], f[2]);
  o.distance = std::max(distance, 1e-4);
  if (cam.fy > 0 && cam.height > 0) o.fov_y_deg = 2.0 * std::atan(0.5 * cam.height / cam.fy) * 180.0 / M_PI;
  const auto c = cam.center();
  const auto fw = orbit_forward(o);
  for (int k = 0; k < 3; ++k) o.target[k] = c[k] + o.distance * fw[k];
  return o;
}

// Controls, as pure updates of an orbit (the viewer feeds them GLFW input).
// Drag: dx, dy in pixels; a drag across the window height turns by about 180 degrees.
inline void orbit_rotate(Orbit& o, double dx_px, double dy_px, uint32_t height) {
  const double k = M_PI / std::max<uint32_t>(height, 1);
  o.yaw += dx_px * k;
  o.pitch = std::clamp(o.pitch + dy_px * k, -kMaxPitchRad, kMaxPitchRad);
}

// Wheel: each notch up moves 10% closer.
inline void orbit_zoom(Orbit& o, double notches) { o.distance = std::max(1e-4, o.distance * std::pow(0.9, notches)); }

// Fly: moves target and eye together along the view's right / down / forward axes by
// `amount` (in units of the current distance).
inline void orbit_fly(Orbit& o, double right, double down, double forward) {
  Camera c = orbit_camera(o, 2, 2);
  for (int k = 0; k < 3; ++k)
    o.target[k] += o.distance * (right * c.R[0 * 3 + k] + down * c.R[1 * 3 + k] + forward * c.R[2 * 3 + k]);
}

}  // namespace evflow::viewer
