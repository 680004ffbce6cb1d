#include "sim/flow_truth.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "io/npy.h"
#include "sim/simulator.h"

namespace evflow::sim {

namespace fs = std::filesystem;

namespace {

Camera camera_of(const nlohmann::json& intr, const nlohmann::json& R, const nlohmann::json& T,
                 const nlohmann::json& size) {
  Camera c;
  c.fx = intr.at(0), c.fy = intr.at(1), c.cx = intr.at(2), c.cy = intr.at(3);
  c.width = size.at(0), c.height = size.at(1);
  for (int i = 0; i < 9; ++i) c.R[i] = R.at(i);
  for (int i = 0; i < 3; ++i) c.t[i] = T.at(i);
  return c;
}

// Pixel positions at normalised time u of the points seen at mid-exposure (x + flow mid -> u).
std::vector<float> positions_at(const nlohmann::json& view, const Camera& mid, const std::vector<float>& depth,
                                double u) {
  const nlohmann::json& sub = view.at("subframes");
  const double t0 = view.at("exposure").at(0), t1 = view.at("exposure").at(1), t = t0 + u * (t1 - t0);
  size_t b = 1;
  while (b + 1 < sub.size() && double(sub[b].at("t")) < t) ++b;
  const double ta = sub[b - 1].at("t"), tb = sub[b].at("t");
  const double a = std::clamp((t - ta) / std::max(tb - ta, 1e-12), 0.0, 1.0);
  const nlohmann::json& gc = view.at("gt_camera");
  auto flow_to = [&](const nlohmann::json& s) {
    return sim::ground_truth_flow(depth, mid, camera_of(gc.at("intrinsics"), s.at("R"), s.at("T"), gc.at("size")));
  };
  const std::vector<float> fa = flow_to(sub[b - 1]), fb = flow_to(sub[b]);
  std::vector<float> pos(fa.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = float((1 - a) * fa[i] + a * fb[i]);
  return pos;
}

// Training view `name`'s entry in the parsed trajectories of `traj`.
const nlohmann::json& train_view(const nlohmann::json& j, const fs::path& traj, const std::string& name) {
  for (const nlohmann::json& view : j.at("train"))
    if (view.at("name") == name) return view;
  throw std::runtime_error(traj.string() + ": no training view '" + name + "'");
}

// A view's true mid-exposure camera.
Camera gt_camera_of(const nlohmann::json& view) {
  const nlohmann::json& gc = view.at("gt_camera");
  return camera_of(gc.at("intrinsics"), gc.at("R"), gc.at("t"), gc.at("size"));
}

// The interval flows of training view `name` from the trajectories parsed from `traj`.
std::vector<std::vector<float>> interval_flow_of(const nlohmann::json& j, const fs::path& traj, const std::string& name,
                                                 const fs::path& depth_file, const std::vector<double>& frame_u) {
  const nlohmann::json& view = train_view(j, traj, name);
  if (view.at("subframes").size() < 2)
    throw std::runtime_error(traj.string() + ": view '" + name + "' has " +
                             std::to_string(view.at("subframes").size()) + " subframes; the flow needs at least 2");
  const Camera mid = gt_camera_of(view);
  const std::vector<double> d = io::read_npy_double(depth_file);
  if (d.size() != size_t(mid.width) * mid.height)
    throw std::runtime_error(depth_file.string() + ": " + std::to_string(d.size()) + " values for a " +
                             std::to_string(mid.width) + "x" + std::to_string(mid.height) + " camera");
  const std::vector<float> depth(d.begin(), d.end());
  std::vector<std::vector<float>> out;
  std::vector<float> prev = positions_at(view, mid, depth, frame_u[0]);
  for (size_t k = 1; k < frame_u.size(); ++k) {
    std::vector<float> cur = positions_at(view, mid, depth, frame_u[k]), flow(cur.size());
    for (size_t i = 0; i < cur.size(); ++i) flow[i] = cur[i] - prev[i];
    out.push_back(std::move(flow));
    prev = std::move(cur);
  }
  return out;
}

// gt/trajectories.json parsed, or nullopt where the dataset has none.
std::optional<nlohmann::json> read_trajectories(const fs::path& traj) {
  if (!fs::exists(traj)) return std::nullopt;
  std::ifstream f(traj);
  try {
    return nlohmann::json::parse(f);
  } catch (const std::exception& e) { throw std::runtime_error(traj.string() + ": " + e.what()); }
}

}  // namespace

std::optional<std::vector<std::vector<float>>> ground_truth_interval_flow(const fs::path& data, const std::string& name,
                                                                          const std::vector<double>& frame_u) {
  const fs::path traj = data / "gt" / "trajectories.json", depth_file = data / "gt" / "depth" / (name + ".npy");
  if (!fs::exists(depth_file)) return std::nullopt;
  const auto j = read_trajectories(traj);
  if (!j) return std::nullopt;
  try {
    return interval_flow_of(*j, traj, name, depth_file, frame_u);
  } catch (const nlohmann::json::exception& e) { throw std::runtime_error(traj.string() + ": " + e.what()); }
}

std::optional<Camera> ground_truth_mid_camera(const fs::path& data, const std::string& name) {
  const fs::path traj = data / "gt" / "trajectories.json";
  const auto j = read_trajectories(traj);
  if (!j) return std::nullopt;
  try {
    return gt_camera_of(train_view(*j, traj, name));
  } catch (const nlohmann::json::exception& e) { throw std::runtime_error(traj.string() + ": " + e.what()); }
}

EndpointError endpoint_error(const std::vector<float>& estimate, const std::vector<float>& truth,
                             const std::vector<uint32_t>& counts) {
  if (truth.size() != counts.size() * 2 || estimate.size() != counts.size() * 2)
    throw std::invalid_argument("flow endpoint error: the ground truth (gt/trajectories.json's camera) has " +
                                std::to_string(truth.size() / 2) + " pixels, the estimate " +
                                std::to_string(estimate.size() / 2) + " and the sensor " +
                                std::to_string(counts.size()));
  EndpointError e;
  for (size_t p = 0; p < counts.size(); ++p) {
    const float tx = truth[p * 2], ty = truth[p * 2 + 1];
    if (!counts[p] || !std::isfinite(tx) || !std::isfinite(ty)) continue;
    e.sum += std::hypot(estimate[p * 2] - tx, estimate[p * 2 + 1] - ty);
    e.truth_sum += std::hypot(tx, ty);
    ++e.n;
  }
  return e;
}

}  // namespace evflow::sim
