// The viewer's orbit camera as pure functions (header-only: the tests include it to render the
// exact view `evflow view` starts with). docs/viewer.md describes the controls.
//
// World convention is OpenCV's (x right, y down, z forward for an identity camera), so world
// "up" is -y. An orbit is a target point, a distance, a yaw (about the up axis) and a pitch
// (positive = the eye above the target, looking down). yaw = pitch = 0 is the identity
// orientation: the eye at target - distance * (0, 0, 1), looking along +z. Yaw and pitch are
// taken in the orbit's frame (`basis`): identity for OpenCV's world; a dataset whose world has
// another up direction gets the frame of its cameras (basis_from_cameras).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

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
  // > 0: an image narrower than this width / height ratio widens its vertical field of view so
  // that the horizontal one stays what fov_y_deg gives at this ratio (a training view's whole
  // width stays in sight in a tall window).
  double fit_aspect = 0;
  // Row-major 3 x 3: world = basis * frame. Its columns are the frame's right, down and
  // yaw-0 forward directions in the world.
  std::array<double, 9> basis{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// basis * v and basis^T * v.
inline std::array<double, 3> to_world(const Orbit& o, const std::array<double, 3>& v) {
  const auto& b = o.basis;
  return {b[0] * v[0] + b[1] * v[1] + b[2] * v[2], b[3] * v[0] + b[4] * v[1] + b[5] * v[2],
          b[6] * v[0] + b[7] * v[1] + b[8] * v[2]};
}
inline std::array<double, 3> to_frame(const Orbit& o, const std::array<double, 3>& v) {
  const auto& b = o.basis;
  return {b[0] * v[0] + b[3] * v[1] + b[6] * v[2], b[1] * v[0] + b[4] * v[1] + b[7] * v[2],
          b[2] * v[0] + b[5] * v[1] + b[8] * v[2]};
}

// Unit vector from the eye to the target (world).
inline std::array<double, 3> orbit_forward(const Orbit& o) {
  const double cp = std::cos(o.pitch);
  return to_world(o, {std::sin(o.yaw) * cp, std::sin(o.pitch), std::cos(o.yaw) * cp});
}

inline std::array<double, 3> orbit_eye(const Orbit& o) {
  auto f = orbit_forward(o);
  return {o.target[0] - o.distance * f[0], o.target[1] - o.distance * f[1], o.target[2] - o.distance * f[2]};
}

// The camera of an orbit for a width x height image (square pixels, principal point at the
// centre, vertical field of view o.fov_y_deg).
inline Camera orbit_camera(const Orbit& o, uint32_t width, uint32_t height) {
  double fov = o.fov_y_deg;
  const double aspect = double(width) / std::max<uint32_t>(height, 1);
  if (o.fit_aspect > aspect)
    fov = 2.0 * std::atan(std::tan(0.5 * fov * M_PI / 180.0) * o.fit_aspect / aspect) * 180.0 / M_PI;
  Camera c = Camera::look_at(width, height, fov, orbit_eye(o), o.target, to_world(o, {0.0, -1.0, 0.0}));
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

// The frame whose down direction is the mean of the cameras' image-down axes and whose yaw-0
// forward is their mean viewing axis (made orthogonal to it): "up" as the cameras hold it.
// Identity when there are no cameras or the means vanish.
inline std::array<double, 9> basis_from_cameras(const std::vector<Camera>& cams) {
  std::array<double, 3> down{0, 0, 0}, fwd{0, 0, 0};
  for (const Camera& c : cams)
    for (int k = 0; k < 3; ++k) {
      down[k] += c.R[3 + k];
      fwd[k] += c.R[6 + k];
    }
  auto norm = [](std::array<double, 3>& v) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 1e-9)) return false;
    for (double& x : v) x /= l;
    return true;
  };
  const std::array<double, 9> identity{1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (!norm(down)) return identity;
  const double d = fwd[0] * down[0] + fwd[1] * down[1] + fwd[2] * down[2];
  for (int k = 0; k < 3; ++k) fwd[k] -= d * down[k];
  if (!norm(fwd)) return identity;
  const std::array<double, 3> right{down[1] * fwd[2] - down[2] * fwd[1], down[2] * fwd[0] - down[0] * fwd[2],
                                    down[0] * fwd[1] - down[1] * fwd[0]};
  return {right[0], down[0], fwd[0], right[1], down[1], fwd[1], right[2], down[2], fwd[2]};
}

// An orbit in frame `basis` whose eye is the camera's centre and which looks along the camera's
// viewing axis, with the camera's vertical field of view (roll is dropped: an orbit keeps the
// frame's up up). The target lies `distance` ahead of the eye. `evflow train --view` starts at
// a training view.
inline Orbit orbit_from_camera(const Camera& cam, double distance,
                               const std::array<double, 9>& basis = {1, 0, 0, 0, 1, 0, 0, 0, 1}) {
  Orbit o;
  o.basis = basis;
  const std::array<double, 3> f = to_frame(o, {cam.R[6], cam.R[7], cam.R[8]});  // viewing axis in the frame
  o.pitch = std::clamp(std::asin(std::clamp(f[1], -1.0, 1.0)), -kMaxPitchRad, kMaxPitchRad);
  o.yaw = std::atan2(f[0], f[2]);
  o.distance = std::max(distance, 1e-4);
  if (cam.fy > 0 && cam.height > 0) {
    o.fov_y_deg = 2.0 * std::atan(0.5 * cam.height / cam.fy) * 180.0 / M_PI;
    o.fit_aspect = double(cam.width) / double(cam.height) * cam.fy / std::max(cam.fx, 1e-9);
  }
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
