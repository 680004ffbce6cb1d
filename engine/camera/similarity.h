// Similarity transforms between point sets (Umeyama's least-squares fit) and the pose error of
// one set of cameras against another after aligning them: how estimated poses (COLMAP's, in a
// frame of its own choosing) compare with reference poses.
#pragma once
#include <array>
#include <vector>

#include "camera/camera.h"
#include "camera/se3.h"

namespace evflow {

using lie::Vec3;

// y = s * R * x + t, R row-major, a rotation (det +1).
struct Similarity {
  double scale = 1;
  std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};
  Vec3 t{0, 0, 0};
  Vec3 apply(const Vec3& x) const;
};

// The similarity minimising sum |dst_i - (s R src_i + t)|^2 (Umeyama 1991: SVD of the
// cross-covariance, with the reflection case turned into the nearest rotation). Throws
// std::invalid_argument when the sets differ in size, hold fewer than 3 points, or src has no
// spread (all points equal).
Similarity umeyama(const std::vector<Vec3>& src, const std::vector<Vec3>& dst);

// Singular value decomposition A = U diag(sv) V^T of a row-major 3x3 matrix (one-sided Jacobi):
// U and V orthogonal, sv >= 0 in decreasing order.
void svd3(const std::array<double, 9>& A, std::array<double, 9>& U, Vec3& sv, std::array<double, 9>& V);

// Errors of `estimated` against `reference` (same views, same order) after the similarity that
// maps the estimated cameras onto the reference ones: fitted (umeyama) to the camera centres and
// to one point per camera `extent` ahead on its optical axis (its distance in the estimated frame
// from the scale of the centres alone), so that orientations fix the rotation where the centres
// nearly lie on a line. Rotation: the angle of
// R_ref * R_est_aligned^T per view, degrees. Translation: the distance between the reference
// centre and the aligned estimated centre, as a percentage of `extent`.
struct PoseErrors {
  Similarity alignment;  // estimated frame -> reference frame
  double rot_mean_deg = 0, rot_max_deg = 0;
  double trans_mean_pct = 0, trans_max_pct = 0;
  std::vector<double> rot_deg, trans_pct;  // per view
  // Frame-free: the angle of (R_est_i R_est_j^T)(R_ref_i R_ref_j^T)^T, the error of each pair's
  // relative rotation, mean over all pairs (no alignment involved).
  double relative_rot_mean_deg = 0;
};
PoseErrors pose_errors(const std::vector<Camera>& estimated, const std::vector<Camera>& reference, double extent);

// The scene extent the translation errors are relative to: the largest distance between two of
// the cameras' centres (at least 1e-12).
double camera_extent(const std::vector<Camera>& cameras);

}  // namespace evflow
