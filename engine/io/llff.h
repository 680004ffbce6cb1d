// LLFF poses_bounds.npy: float64 N x 17 rows = 3x5 matrix [R | c | (h, w, f)] (row-major, the
// rotation's columns are the camera's down, right, back axes in world coordinates, c the camera
// centre) followed by near and far depth bounds.
#pragma once
#include <array>
#include <filesystem>
#include <vector>

#include "camera/camera.h"

namespace evflow::io {

using LlffRow = std::array<double, 17>;

struct PosesBounds {
  std::vector<LlffRow> rows;      // exactly as stored in the file
  std::vector<Camera> cameras;    // converted rows (see llff_row_to_camera)
  std::vector<double> near, far;  // per row
};

// Row -> OpenCV camera (x right, y down, z forward; world_to_camera R, t):
//   camera-to-world axes: x = right = column 1, y = down = column 0, z = forward = -column 2;
//   R = rows (col1, col0, -col2) (exact), t = -R c (rounded once, long double accumulation);
//   width = w, height = h, fx = fy = f, cx = w / 2, cy = h / 2 (principal point at the centre).
// near_plane / far_plane are left at Camera's defaults.
Camera llff_row_to_camera(const LlffRow& row);
// Camera -> row: the inverse (rotation and h, w, f exact; c = -R^T t rounded once); f = fx.
// fy, cx, cy are not representable in LLFF and are dropped.
LlffRow camera_to_llff_row(const Camera& camera, double near, double far);

// Throws std::runtime_error naming the file unless it is a readable N x 17 (or 17-element)
// float32/float64 array with finite values, h, w, f > 0 and integer h, w.
PosesBounds read_poses_bounds(const std::filesystem::path& path);
// Writes rows as float64 N x 17 (atomic); reading them back gives the same bits.
void write_poses_bounds(const std::filesystem::path& path, const std::vector<LlffRow>& rows);
void write_poses_bounds(const std::filesystem::path& path, const std::vector<Camera>& cameras,
                        const std::vector<double>& near, const std::vector<double>& far);

}  // namespace evflow::io
