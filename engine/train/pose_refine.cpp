#include "train/pose_refine.h"

#include <cmath>
#include <limits>

#include "camera/se3.h"
#include "loss/image_losses.h"
#include "optim/host_adam.h"

namespace evflow {

PoseRefineResult refine_pose(gpu::Context& ctx, Rasterizer& raster, const GaussianBuffers& params, const Camera& start,
                             const gpu::Buffer& target, const PoseRefineOptions& o) {
  const uint32_t W = start.width, H = start.height;
  const uint64_t hw = uint64_t(W) * H;
  if (target.size() < hw * 12) throw std::invalid_argument("refine_pose: target holds less than 3 x H x W floats");
  BlendLoss loss(ctx, ImageShape{3, H, W}, o.ssim_lambda, 1.0f);
  gpu::Buffer v_rgb(ctx, hw * 12, "refine_v_rgb"), v_alpha(ctx, hw * 4, "refine_v_alpha");
  v_alpha.write(std::vector<float>(hw, 0.0f));
  GaussianBuffers grads(ctx, params.count, params.sh_degree, "refine_v_");
  RenderState raster_state(ctx);
  gpu::Commands cmd(ctx);
  lie::Vec6 delta{}, m{}, v{};
  PoseRefineResult best{start, 0, std::numeric_limits<double>::infinity(), {}};
  for (uint32_t it = 0; it <= o.iterations; ++it) {
    const Camera cam = start.perturbed(delta);
    raster.forward(params, cam, o.settings, raster_state);
    loss.record(cmd, raster_state.outputs().rgb, target, v_rgb, false);
    cmd.submit();
    const double l = loss.value();
    if (it == 0) best.first_loss = l;
    if (!std::isfinite(l)) break;
    if (l < best.last_loss) best = {cam, best.first_loss, l, delta};
    if (it == o.iterations) break;
    raster.backward(raster_state, params, v_rgb, v_alpha, grads, false);
    auto g = raster.pose_gradient();
    const lie::Vec6 gd =
        lie::mul_transposed(lie::se3_right_jacobian(delta), lie::Vec6{g[0], g[1], g[2], g[3], g[4], g[5]});
    host_adam_step(delta.data(), gd.data(), m.data(), v.data(), 6, it + 1, o.lr);
  }
  return best;
}

}  // namespace evflow
