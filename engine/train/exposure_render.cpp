#include "train/exposure_render.h"

#include <stdexcept>

namespace evflow {

ExposureRender::ExposureRender(gpu::Context& ctx, uint32_t frames) {
  for (uint32_t i = 0; i < frames; ++i) states_.emplace_back(ctx);
}

void ExposureRender::forward(Rasterizer& raster, const GaussianBuffers& params, const std::vector<Camera>& cameras,
                             const RenderSettings& settings) {
  if (cameras.size() != states_.size()) throw std::invalid_argument("ExposureRender: one camera per frame expected");
  std::vector<RenderState*> states;
  for (RenderState& s : states_) states.push_back(&s);
  raster.forward(params, cameras, settings, states);
}

std::vector<const gpu::Buffer*> ExposureRender::images() const {
  std::vector<const gpu::Buffer*> out;
  for (auto& s : states_) out.push_back(&s.outputs().rgb);
  return out;
}

std::vector<lie::Vec6> ExposureRender::backward(Rasterizer& raster, const GaussianBuffers& params,
                                                const std::vector<const gpu::Buffer*>& v_rgb,
                                                const gpu::Buffer& v_alpha, GaussianBuffers& grads) const {
  std::vector<const RenderState*> states;
  for (const RenderState& s : states_) states.push_back(&s);
  std::vector<lie::Vec6> pose;
  for (const auto& g : raster.backward(states, params, v_rgb, v_alpha, grads))
    pose.push_back({g[0], g[1], g[2], g[3], g[4], g[5]});
  return pose;
}

}  // namespace evflow
