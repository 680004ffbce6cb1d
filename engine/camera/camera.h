// The pinhole camera shared by io/, splat/, sim/, train/ and the viewer.
#pragma once
#include <array>
#include <cstdint>

namespace evflow {

// A pinhole camera. world_to_camera maps world points into the camera frame (x right, y down,
// z forward, OpenCV convention): p_c = R * p_w + t. R is row-major.
struct Camera {
  uint32_t width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> t{0, 0, 0};
  double near_plane = 0.01;
  double far_plane = 1e10;

  std::array<double, 3> center() const;  // camera centre in world: -R^T t
  // Returns the camera with c2w' = c2w * Exp(delta), delta = (rho, phi) in se(3), translation
  // first; equivalently w2c' = Exp(-delta) * w2c. This is the convention of the pose gradient.
  Camera perturbed(const std::array<double, 6>& delta) const;
  // Camera at `eye` looking at `target` with `up` (world) roughly up in the image.
  static Camera look_at(uint32_t width, uint32_t height, double fov_y_deg, const std::array<double, 3>& eye,
                        const std::array<double, 3>& target, const std::array<double, 3>& up = {0, 1, 0});
};

}  // namespace evflow
