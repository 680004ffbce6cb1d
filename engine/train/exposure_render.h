// The exposure of a training step as the splats render it: one render per frame (2N+1 virtual
// frames along the view's exposure, or one), each kept in its own render state for the
// backward pass, which runs through one rasterizer frame after frame.
#pragma once
#include <cstdint>
#include <vector>

#include "camera/se3.h"
#include "splat/rasterizer.h"

namespace evflow {

class ExposureRender {
 public:
  ExposureRender(gpu::Context& ctx, uint32_t frames);
  uint32_t frames() const { return uint32_t(states_.size()); }

  // Renders frame i at cameras[i] (one per frame), each into its own state.
  void forward(Rasterizer& raster, const GaussianBuffers& params, const std::vector<Camera>& cameras,
               const RenderSettings& settings);
  // The renders (display-referred sRGB, planar), in frame order.
  std::vector<const gpu::Buffer*> images() const;
  // Back through every frame in order: frame i's image gradient is v_rgb[i]; the parameter
  // gradients and the screen-gradient norms of all frames add up in `grads` and
  // raster.grad2d_norm(). Returns each frame's pose gradient (se(3), translation first).
  std::vector<lie::Vec6> backward(Rasterizer& raster, const GaussianBuffers& params,
                                  const std::vector<const gpu::Buffer*>& v_rgb, const gpu::Buffer& v_alpha,
                                  GaussianBuffers& grads) const;

 private:
  std::vector<RenderState> states_;
};

}  // namespace evflow
