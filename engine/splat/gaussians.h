// Host-side inputs of the rasterizer: the Gaussian cloud, the camera and the render settings.
#pragma once
#include <array>

#include "camera/camera.h"
#include "cloud/gaussian_cloud.h"

namespace evflow {

struct RenderSettings {
  std::array<float, 3> background{0, 0, 0};
  bool antialiased = false;  // opacity *= sqrt(det(S2) / det(S2 + 0.3 I))
  int sh_degree = -1;        // active degree; -1 = the cloud's degree
  // Write the depth plane (RasterOutputs::depth). Without, the block forward (CPU drivers) keeps
  // no depth sum, a few percent faster, and leaves the plane as it was; other kernels write it.
  bool depth = true;
};

}  // namespace evflow
