// Renders a Scene on the GPU with compute shaders (shaders/sim): linear RGB + camera depth.
// Coverage: a pixel is covered when the ray through its centre meets the triangle (watertight);
// nearest surface wins (ties: lowest triangle index). Shading: trilinear (mip-mapped) base-colour
// texture at 4 sub-pixel rays (texture anti-aliasing), times the material factor, times
// (ambient + (1 - ambient) * max(0, n . light)) with the face normal turned towards the camera.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "camera/camera.h"
#include "gpu/commands.h"
#include "scan/prefix_sum.h"
#include "sim/scene.h"

namespace evflow::sim {

struct ShadingParams {
  std::array<float, 3> light_dir{0.35f, 0.8f, 0.5f};  // towards the light, world (normalised on use)
  float ambient = 0.35f;
  std::array<float, 3> background{0.02f, 0.025f, 0.035f};
  int texture_samples = 4;  // 1 or 4 rays per pixel for the texture lookup
};

struct Frame {
  uint32_t width = 0, height = 0;
  std::vector<float> rgb;    // H*W*3 linear
  std::vector<float> depth;  // H*W camera z, 0 where no surface was hit (background)
};

class MeshRenderer {
 public:
  MeshRenderer(gpu::Context& ctx, const Scene& scene, const ShadingParams& shading = {});
  Frame render(const Camera& cam);
  gpu::Context& context() const { return ctx_; }
  // Triangles whose pixel box spans at most `px` pixels each way are rasterized by one invocation
  // each (the default, 8, suits heavy meshes); the others by a workgroup per 16x16 tile. 0 sends
  // every triangle to the tiles. The image is the same either way.
  void set_small_triangle_box(uint32_t px) { small_box_ = px; }
  // GPU time per stage (ms) of the last render, in order (setup, scan, clear, raster small /
  // tiles per pass, shade).
  const std::vector<std::pair<std::string, double>>& stage_ms() const { return stage_ms_; }
  const ShadingParams& shading() const { return shading_; }

 private:
  gpu::Context& ctx_;
  ShadingParams shading_;
  uint32_t n_tris_ = 0;
  uint32_t small_box_;
  gpu::Commands cmd_;
  PrefixSum scan_;
  std::vector<std::pair<std::string, double>> stage_ms_;
  gpu::Buffer tris_, materials_, texels_, decode_, cam_, boxes_, counts_, offsets_, depth_, ids_, image_;
};

}  // namespace evflow::sim
