#include "train/model_flow.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace evflow {

std::vector<float> depth_flow(const std::vector<float>& depth, const std::vector<float>& alpha, const Camera& a,
                              const Camera& b, float min_alpha) {
  const uint32_t W = a.width, H = a.height;
  const size_t hw = size_t(W) * H;
  if (depth.size() != hw || alpha.size() != hw)
    throw std::invalid_argument("depth_flow: depth and alpha need " + std::to_string(hw) + " values for a " +
                                std::to_string(W) + "x" + std::to_string(H) + " camera");
  std::vector<float> flow(hw * 2, NAN);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t p = size_t(y) * W + x;
      const double z = depth[p];
      if (!(alpha[p] >= min_alpha) || !(z > 0) || !std::isfinite(z)) continue;
      // Camera a's coordinates, then world: X = R_a^T (Xc - t_a).
      const double xc[3] = {(x + 0.5 - a.cx) / a.fx * z - a.t[0], (y + 0.5 - a.cy) / a.fy * z - a.t[1], z - a.t[2]};
      double X[3];
      for (int k = 0; k < 3; ++k) X[k] = a.R[k] * xc[0] + a.R[3 + k] * xc[1] + a.R[6 + k] * xc[2];
      double q[3];
      for (int k = 0; k < 3; ++k) q[k] = b.R[3 * k] * X[0] + b.R[3 * k + 1] * X[1] + b.R[3 * k + 2] * X[2] + b.t[k];
      if (!(q[2] > 1e-9)) continue;
      flow[2 * p] = float(b.fx * q[0] / q[2] + b.cx - (x + 0.5));
      flow[2 * p + 1] = float(b.fy * q[1] / q[2] + b.cy - (y + 0.5));
    }
  return flow;
}

std::vector<std::vector<float>> ModelFlow::intervals(Rasterizer& raster, const GaussianBuffers& params,
                                                     const std::vector<Camera>& cams, const RenderSettings& settings) {
  std::vector<std::vector<float>> out;
  RenderSettings with_depth = settings;
  with_depth.depth = true;
  for (size_t i = 0; i + 1 < cams.size(); ++i) {
    raster.forward(params, cams[i], with_depth, state_);
    const size_t hw = size_t(cams[i].width) * cams[i].height;
    const std::vector<float> depth = state_.outputs().depth.read<float>(hw);
    const std::vector<float> alpha = state_.outputs().alpha.read<float>(hw);
    out.push_back(depth_flow(depth, alpha, cams[i], cams[i + 1]));
  }
  return out;
}

}  // namespace evflow
