// evflow fit-demo: renders a built-in synthetic scene from a few views, then fits a fresh set of
// Gaussians to those images by gradient descent through the rasterizer's backward (L2 image
// loss, Adam on the host), and reports the PSNR before and after. A self-check of the whole
// differentiable renderer end to end.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "io/image.h"
#include "splat/rasterizer.h"
#include "splat/synthetic.h"

namespace evflow::app {

namespace {

struct HostAdam {
  std::vector<float> m, v;
  void step(std::vector<float>& p, const std::vector<float>& g, float lr, int t) {
    if (m.size() != p.size()) {
      m.assign(p.size(), 0.f);
      v.assign(p.size(), 0.f);
    }
    const float b1 = 0.9f, b2 = 0.999f;
    const float c1 = 1.f - std::pow(b1, float(t)), c2 = 1.f - std::pow(b2, float(t));
    for (size_t i = 0; i < p.size(); ++i) {
      m[i] = b1 * m[i] + (1 - b1) * g[i];
      v[i] = b2 * v[i] + (1 - b2) * g[i] * g[i];
      p[i] -= lr * (m[i] / c1) / (std::sqrt(v[i] / c2) + 1e-15f);
    }
  }
};

}  // namespace

static int run_fit_demo(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf(
        "usage: evflow fit-demo [--out DIR] [--steps 300] [--width 160] [--height 120] [--gaussians 3000]\n"
        "                       [--views 4] [--device N|name]\n");
    return 0;
  }
  const std::string out = p.value("--out", "runs/fit-demo");
  const int steps = int(p.integer("--steps", 300, 1, 10000000));
  const auto [W, H] = p.image_size({160, 120});
  const size_t N = size_t(p.integer("--gaussians", 3000, 1, 100000000));
  const int views = int(p.integer("--views", 4, 1, 1000));
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  gpu::Context ctx(o);
  std::printf("fit-demo on %s: %zu Gaussians, %d views of %ux%u, %d steps\n", ctx.caps().name.c_str(), N, views, W, H,
              steps);

  // Views on an arc looking at the scene centre (depth ~6).
  std::vector<Camera> cams;
  for (int v = 0; v < views; ++v) {
    double ang = (v - 0.5 * (views - 1)) * 0.08;
    cams.push_back(
        Camera::look_at(W, H, 60.0, {6 * std::sin(ang), 0.2 * v, 6 - 6 * std::cos(ang)}, {0, 0, 6}, {0, -1, 0}));
  }
  GaussianCloud truth = synthetic_cloud(7, N, 1, cams[0]);
  GaussianCloud fit = synthetic_cloud(8, N, 1, cams[0]);
  const size_t hw = size_t(W) * H;
  RenderSettings s;
  Rasterizer r(ctx);
  RenderState rs(ctx);
  std::vector<std::vector<float>> targets;
  {
    GaussianBuffers tb(ctx, N, 1, "truth_");
    tb.upload(truth);
    for (auto& c : cams) {
      r.forward(tb, c, s, rs);
      targets.push_back(rs.outputs().rgb.read<float>(3 * hw));
    }
  }
  GaussianBuffers params(ctx, N, 1, "p_"), grads(ctx, N, 1, "v_");
  gpu::Buffer v_rgb(ctx, hw * 12, "v_rgb"), v_alpha(ctx, hw * 4, "v_alpha");
  v_alpha.write(std::vector<float>(hw, 0.f));
  HostAdam am, al, aq, ao, as;
  auto psnr_all = [&](const GaussianCloud& c, bool save, const std::string& tag) {
    params.upload(c);
    double mse = 0;
    for (size_t v = 0; v < cams.size(); ++v) {
      r.forward(params, cams[v], s, rs);
      auto img = rs.outputs().rgb.read<float>(3 * hw);
      for (size_t i = 0; i < img.size(); ++i) mse += double(img[i] - targets[v][i]) * (img[i] - targets[v][i]);
      if (save) {
        io::write_png(std::filesystem::path(out) / (tag + "_view" + std::to_string(v) + ".png"),
                      io::image_from_render(img, W, H));
        if (tag == "before")
          io::write_png(std::filesystem::path(out) / ("target_view" + std::to_string(v) + ".png"),
                        io::image_from_render(targets[v], W, H));
      }
    }
    mse /= double(cams.size() * 3 * hw);
    return -10.0 * std::log10(std::max(mse, 1e-12));
  };
  std::filesystem::create_directories(out);
  const double before = psnr_all(fit, true, "before");
  auto t0 = std::chrono::steady_clock::now();
  for (int it = 1; it <= steps; ++it) {
    const size_t v = size_t(it) % cams.size();
    params.upload(fit);
    r.forward(params, cams[v], s, rs);
    auto img = rs.outputs().rgb.read<float>(3 * hw);
    std::vector<float> g(img.size());
    double loss = 0;
    for (size_t i = 0; i < img.size(); ++i) {
      float d = img[i] - targets[v][i];
      loss += double(d) * d;
      g[i] = 2.f * d / float(img.size());
    }
    v_rgb.write(g);
    r.backward(rs, params, v_rgb, v_alpha, grads);
    GaussianCloud gc = grads.download();
    am.step(fit.means, gc.means, 2e-3f, it);
    al.step(fit.log_scales, gc.log_scales, 5e-3f, it);
    aq.step(fit.quats, gc.quats, 1e-3f, it);
    ao.step(fit.opacity_logits, gc.opacity_logits, 5e-2f, it);
    as.step(fit.sh, gc.sh, 2.5e-3f, it);
    if (it % 50 == 0 || it == steps)
      std::printf("  step %4d  view %zu  L2 %.5f  (%.1f it/s)\n", it, v, loss / img.size(),
                  it / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  const double after = psnr_all(fit, true, "after");
  std::printf("PSNR over the %d views: %.2f dB before, %.2f dB after fitting; images in %s\n", views, before, after,
              out.c_str());
  return after > before ? 0 : 1;
}

static Command reg("fit-demo", "render a built-in scene, fit Gaussians to it through the differentiable rasterizer",
                   run_fit_demo);

}  // namespace evflow::app
