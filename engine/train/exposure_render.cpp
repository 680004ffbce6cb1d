#include "train/exposure_render.h"

#include <stdexcept>

namespace evflow {

ExposureRender::ExposureRender(gpu::Context& ctx, uint32_t frames) {
  for (uint32_t i = 0; i < frames; ++i) states_.emplace_back(ctx);
}

void ExposureRender::forward(Rasterizer& raster, const GaussianBuffers& params, const std::vector<Camera>& cameras,
                             const RenderSettings& settings) {
  if (cameras.size() != states_.size()) throw std::invalid_argument("ExposureRender: one camera per frame expected");
  for (size_t i = 0; i < states_.size(); ++i) raster.forward(params, cameras[i], settings, states_[i]);
}

std::vector<const gpu::Buffer*> ExposureRender::images() const {
  std::vector<const gpu::Buffer*> out;
  for (auto& s : states_) out.push_back(&s.outputs().rgb);
  return out;
}

std::vector<lie::Vec6> ExposureRender::backward(Rasterizer& raster, const GaussianBuffers& params,
                                                const std::vector<const gpu::Buffer*>& v_rgb,
                                                const gpu::Buffer& v_alpha, GaussianBuffers& grads) const {
  std::vector<lie::Vec6> pose;
  for (size_t i = 0; i < states_.size(); ++i) {
    raster.backward(states_[i], params, *v_rgb[i], v_alpha, grads, i > 0);
    const auto g = raster.pose_gradient();
    pose.push_back({g[0], g[1], g[2], g[3], g[4], g[5]});
  }
  return pose;
}

}  // namespace evflow
