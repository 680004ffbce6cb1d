// Camera pose refinement with the Gaussians frozen: the test-pose step of novel-view evaluation
// (REFERENCE.md §2: the peers re-optimise each test camera before measuring). Minimises the
// blend loss (1 - l) L1 + l D-SSIM between the render and the target image over an se(3) delta,
// c2w' = c2w Exp(delta), with Adam on the host; the gradient is the rasterizer's exact pose
// gradient chained through the right Jacobian of Exp.
#pragma once
#include <cstdint>

#include "gpu/buffer.h"
#include "splat/rasterizer.h"

namespace evflow {

struct PoseRefineOptions {
  uint32_t iterations = 60;
  double lr = 2e-3;  // Adam step on the se(3) delta (translation in scene units, rotation in rad)
  float ssim_lambda = 0.2f;
  RenderSettings settings;
};

struct PoseRefineResult {
  Camera camera;  // the refined camera
  double first_loss = 0, last_loss = 0;
  std::array<double, 6> delta{};
};

// `target` is planar RGB (3 x H x W) of the camera's size. Returns the camera with the lowest loss seen.
PoseRefineResult refine_pose(gpu::Context& ctx, Rasterizer& raster, const GaussianBuffers& params, const Camera& start,
                             const gpu::Buffer& target, const PoseRefineOptions& options);

}  // namespace evflow
