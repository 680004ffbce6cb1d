#include "train/synthetic_dataset.h"

#include <cmath>

#include "io/image.h"
#include "splat/rasterizer.h"
#include "splat/synthetic.h"

namespace evflow {

io::Dataset render_synthetic_dataset(gpu::Context& ctx, uint32_t w, uint32_t h, int n_train, int n_novel,
                                     size_t gaussians, uint64_t seed) {
  io::Dataset d;
  d.layout = "synthetic";
  d.near = 1.0;
  d.far = 12.0;
  Camera c0 = Camera::look_at(w, h, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  GaussianCloud truth = synthetic_cloud(seed, gaussians, 0, c0);
  GaussianBuffers gt(ctx, truth.size(), 0, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  for (int i = 0; i < n_train + n_novel; ++i) {
    const double ang =
        (i < n_train ? (i - 0.5 * (n_train - 1)) / n_train : (i - n_train + 0.5 - 0.5 * n_novel) / n_novel * 0.8) * 0.5;
    Camera cam = Camera::look_at(w, h, 60.0, {6 * std::sin(ang), 0.3 * std::cos(3.0 * i), 6 - 6 * std::cos(ang)},
                                 {0, 0, 6}, {0, -1, 0});
    r.forward(gt, cam, RenderSettings{}, rs);
    io::View v;
    v.name = (i < n_train ? "train" : "novel") + std::to_string(i);
    v.camera = cam;
    io::Image img = io::image_from_render(rs.outputs().rgb.read<float>(size_t(w) * h * 3), w, h);
    v.sharp_mid = img;
    if (i < n_train) {
      v.blurry = std::move(img);
      d.train.push_back(std::move(v));
    } else {
      d.novel.push_back(std::move(v));
    }
  }
  return d;
}

}  // namespace evflow
