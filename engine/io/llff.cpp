#include "io/llff.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "io/npy.h"

namespace evflow::io {

namespace fs = std::filesystem;

// Row-major 3x5 at row[0..14]: element (i, j) = row[i * 5 + j].
Camera llff_row_to_camera(const LlffRow& row) {
  auto m = [&](int i, int j) { return row[i * 5 + j]; };
  Camera cam;
  cam.height = static_cast<uint32_t>(std::llround(m(0, 4)));
  cam.width = static_cast<uint32_t>(std::llround(m(1, 4)));
  cam.fx = cam.fy = m(2, 4);
  cam.cx = 0.5 * cam.width;
  cam.cy = 0.5 * cam.height;
  for (int i = 0; i < 3; ++i) {
    cam.R[0 * 3 + i] = m(i, 1);   // camera x axis (right) in world = LLFF column 1
    cam.R[1 * 3 + i] = m(i, 0);   // camera y axis (down) = column 0
    cam.R[2 * 3 + i] = -m(i, 2);  // camera z axis (forward) = -column 2 (back)
  }
  for (int r = 0; r < 3; ++r) {
    long double s = 0;
    for (int i = 0; i < 3; ++i) s += static_cast<long double>(cam.R[r * 3 + i]) * m(i, 3);
    cam.t[r] = static_cast<double>(-s);
  }
  return cam;
}

LlffRow camera_to_llff_row(const Camera& cam, double near, double far) {
  LlffRow row{};
  auto m = [&](int i, int j) -> double& { return row[i * 5 + j]; };
  for (int i = 0; i < 3; ++i) {
    m(i, 1) = cam.R[0 * 3 + i];
    m(i, 0) = cam.R[1 * 3 + i];
    m(i, 2) = -cam.R[2 * 3 + i];
    long double s = 0;
    for (int r = 0; r < 3; ++r) s += static_cast<long double>(cam.R[r * 3 + i]) * cam.t[r];
    m(i, 3) = static_cast<double>(-s);
  }
  m(0, 4) = cam.height;
  m(1, 4) = cam.width;
  m(2, 4) = cam.fx;
  row[15] = near;
  row[16] = far;
  return row;
}

PosesBounds read_poses_bounds(const fs::path& path) {
  NpyArray a = read_npy(path);
  if (a.dtype != DType::f8 && a.dtype != DType::f4)
    throw std::runtime_error(path.string() + ": poses_bounds must be float64 (or float32), found dtype " +
                             dtype_descr(a.dtype));
  size_t n;
  if (a.shape.size() == 2 && a.shape[1] == 17)
    n = a.shape[0];
  else if (a.shape.size() == 1 && a.shape[0] == 17)
    n = 1;
  else {
    std::string s;
    for (size_t i = 0; i < a.shape.size(); ++i) s += (i ? " x " : "") + std::to_string(a.shape[i]);
    throw std::runtime_error(path.string() + ": poses_bounds must be an N x 17 array, found shape " +
                             (s.empty() ? "()" : s));
  }
  std::vector<double> v = a.to_double();
  PosesBounds pb;
  pb.rows.resize(n);
  for (size_t k = 0; k < n; ++k) {
    for (int j = 0; j < 17; ++j) {
      pb.rows[k][j] = v[k * 17 + j];
      if (!std::isfinite(v[k * 17 + j]))
        throw std::runtime_error(path.string() + ": row " + std::to_string(k) + " has a non-finite value");
    }
    const LlffRow& r = pb.rows[k];
    const double h = r[4], w = r[9], f = r[14];
    if (!(h > 0 && w > 0 && f > 0) || h != std::round(h) || w != std::round(w) || h > 1e6 || w > 1e6)
      throw std::runtime_error(path.string() + ": row " + std::to_string(k) + " has an invalid (h, w, f) = (" +
                               std::to_string(h) + ", " + std::to_string(w) + ", " + std::to_string(f) + ")");
    pb.cameras.push_back(llff_row_to_camera(r));
    pb.near.push_back(r[15]);
    pb.far.push_back(r[16]);
  }
  return pb;
}

void write_poses_bounds(const fs::path& path, const std::vector<LlffRow>& rows) {
  std::vector<double> flat;
  flat.reserve(rows.size() * 17);
  for (const auto& r : rows) flat.insert(flat.end(), r.begin(), r.end());
  write_npy(path, {rows.size(), 17}, flat);
}

void write_poses_bounds(const fs::path& path, const std::vector<Camera>& cameras, const std::vector<double>& near,
                        const std::vector<double>& far) {
  if (near.size() != cameras.size() || far.size() != cameras.size())
    throw std::invalid_argument(path.string() + ": write_poses_bounds: " + std::to_string(cameras.size()) +
                                " cameras but " + std::to_string(near.size()) + " near and " +
                                std::to_string(far.size()) + " far bounds");
  std::vector<LlffRow> rows;
  for (size_t i = 0; i < cameras.size(); ++i) rows.push_back(camera_to_llff_row(cameras[i], near[i], far[i]));
  write_poses_bounds(path, rows);
}

}  // namespace evflow::io
