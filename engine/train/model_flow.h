// Optical flow from the current splats (flow=model; docs/flow.md): each exposure interval's
// displacement field d_i(x) by geometry instead of by events. The splats' expected depth is
// rendered at the interval's first virtual frame t_i, every pixel centre is lifted to 3D with
// the pose at t_i and projected with the pose at t_{i+1}. Exact for a static scene once the
// splats' geometry and the trajectory are right.
#pragma once
#include <vector>

#include "camera/camera.h"
#include "splat/rasterizer.h"

namespace evflow {

// Pixels whose accumulated opacity is below this get no model flow (NaN): no surface there.
constexpr float kModelFlowMinAlpha = 0.5f;

// The displacement from camera a to camera b of the surface seen at each pixel of a: the pixel
// centre (x + 0.5, y + 0.5) at depth `depth` (camera a's z) moved to world by a's pose and
// projected by b's. H * W * 2, u and v interleaved; NaN where alpha < min_alpha, the depth is not
// positive or the point is not in front of b.
std::vector<float> depth_flow(const std::vector<float>& depth, const std::vector<float>& alpha, const Camera& a,
                              const Camera& b, float min_alpha = kModelFlowMinAlpha);

// Renders the splats' depth at a sequence of cameras (the virtual frames of one exposure) and
// returns the flow of each consecutive pair, cams.size() - 1 fields.
class ModelFlow {
 public:
  explicit ModelFlow(gpu::Context& ctx) : state_(ctx) {}
  std::vector<std::vector<float>> intervals(Rasterizer& raster, const GaussianBuffers& params,
                                            const std::vector<Camera>& cams, const RenderSettings& settings);

 private:
  RenderState state_;
};

}  // namespace evflow
