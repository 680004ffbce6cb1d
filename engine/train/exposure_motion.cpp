#include "train/exposure_motion.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "io/npy.h"
#include "sim/flow_truth.h"
#include "train/model_flow.h"

namespace evflow {

namespace fs = std::filesystem;

std::optional<ExposureMotion> exposure_motion(const fs::path& data, const std::string& view, const Camera& start,
                                              const Camera& mid, const Camera& end) {
  const auto truth = sim::ground_truth_interval_flow(data, view, {0.0, 1.0});
  const auto true_mid = sim::ground_truth_mid_camera(data, view);
  if (!truth || !true_mid) return std::nullopt;
  const fs::path depth_file = data / "gt" / "depth" / (view + ".npy");
  const std::vector<double> d = io::read_npy_double(depth_file);
  if (d.size() != size_t(mid.width) * mid.height)
    throw std::runtime_error(depth_file.string() + ": " + std::to_string(d.size()) + " values for a " +
                             std::to_string(mid.width) + "x" + std::to_string(mid.height) + " camera");
  const std::vector<float> depth(d.begin(), d.end()), alpha(depth.size(), 1.0f);
  const std::vector<float> to_start = depth_flow(depth, alpha, mid, start), to_end = depth_flow(depth, alpha, mid, end);
  const std::vector<float> misplaced = depth_flow(depth, alpha, *true_mid, mid);
  const std::vector<float>& gt = truth->front();
  ExposureMotion m;
  for (size_t i = 0; i < depth.size(); ++i) {
    const double lu = double(to_end[2 * i]) - to_start[2 * i], lv = double(to_end[2 * i + 1]) - to_start[2 * i + 1];
    const double tu = gt[2 * i], tv = gt[2 * i + 1];
    const double mu = misplaced[2 * i], mv = misplaced[2 * i + 1];
    if (!std::isfinite(lu) || !std::isfinite(lv) || !std::isfinite(tu) || !std::isfinite(tv) || !std::isfinite(mu) ||
        !std::isfinite(mv))
      continue;
    ++m.pixels;
    m.truth_px += std::hypot(tu, tv);
    m.error_px += std::hypot(lu - tu, lv - tv);
    m.reversed_error_px += std::hypot(lu + tu, lv + tv);
    m.mid_error_px += std::hypot(mu, mv);
  }
  if (m.pixels) {
    m.truth_px /= double(m.pixels);
    m.error_px /= double(m.pixels);
    m.reversed_error_px /= double(m.pixels);
    m.mid_error_px /= double(m.pixels);
  }
  return m;
}

}  // namespace evflow
