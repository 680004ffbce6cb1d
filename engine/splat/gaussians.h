// Host-side Gaussian splats and cameras: the parameter layout shared by io/, splat/, tests.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace evflow {

inline constexpr int kMaxShDegree = 3;
inline constexpr int sh_coeff_count(int degree) { return (degree + 1) * (degree + 1); }

// Parameters are stored pre-activation (REFERENCE.md §1):
//   means          [N][3]  world position
//   log_scales     [N][3]  log of the standard deviations along the Gaussian's axes
//   quats          [N][4]  unnormalised rotation quaternion, (w, x, y, z)
//   opacity_logits [N]     sigmoid() gives opacity
//   sh             [N][K][3], K = (sh_degree+1)^2: coefficient k of channel c at (n*K + k)*3 + c;
//                  k = 0 is the DC term; colour = sum_k Y_k(dir) * sh[k] + 0.5, clamped at 0.
struct GaussianCloud {
  int sh_degree = 0;
  std::vector<float> means, log_scales, quats, opacity_logits, sh;

  size_t size() const { return opacity_logits.size(); }
  int coeffs() const { return sh_coeff_count(sh_degree); }
  void resize(size_t n, int degree);
  // Throws std::invalid_argument naming `what` when sizes disagree or a value is not finite.
  void validate(const std::string& what) const;
};

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

struct RenderSettings {
  std::array<float, 3> background{0, 0, 0};
  bool antialiased = false;  // opacity *= sqrt(det(S2) / det(S2 + 0.3 I))
  int sh_degree = -1;        // active degree; -1 = the cloud's degree
};

}  // namespace evflow
