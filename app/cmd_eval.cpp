// evflow eval RUN [--data DIR]: PSNR / SSIM of the trained Gaussians against the dataset's sharp
// images: the deblur score (each training view's camera vs its mid-exposure ground truth) and
// the novel-view score, on 8-bit sRGB images as the peers score them (metrics/srgb_metrics.h).
// Writes RUN/eval.json, RUN/eval.md and the scored renders as RUN/eval/<set>/<view>.png.
#include <cstdio>
#include <sstream>

#include "camera/trajectory.h"
#include "cli.h"
#include "io/atomic_file.h"
#include "ldi_eval.h"
#include "metrics/srgb_metrics.h"
#include "run_files.h"
#include "splat/rasterizer.h"
#include "train/exposure_motion.h"
#include "train/pose_refine.h"
#include "train/trainer.h"

namespace evflow::app {

namespace fs = std::filesystem;

// With the simulator's ground truth: how training view `index`'s learned exposure moves the image
// against the true motion (train/exposure_motion.h); null without a learned trajectory or truth.
static nlohmann::json motion_json(const RunFolder& run, const io::Dataset& data, size_t index, int& reversed,
                                  double& mid_error) {
  const auto& trajs = run.checkpoint.trajectories;
  if (trajs.empty() || trajs[index].knots.size() == 6) return nullptr;
  const io::View& v = data.train[index];
  const auto m = exposure_motion(data.root, v.name, run.learned_camera(v, index, 0.0),
                                 run.learned_camera(v, index, 0.5), run.learned_camera(v, index, 1.0));
  if (!m) return nullptr;
  reversed += m->reversed();
  mid_error += m->mid_error_px;
  return {{"truth_px", m->truth_px},
          {"error_px", m->error_px},
          {"reversed", m->reversed()},
          {"mid_error_px", m->mid_error_px}};
}

// Scores of one set of views, with everything each view's scoring needs.
struct Scorer {
  gpu::Context& ctx;
  const RunFolder& run;
  const io::Dataset& data;
  const GaussianBuffers& params;
  Rasterizer& r;
  RenderState& rs;
  RenderSettings s;
  uint32_t refine_iters = 0;
  nlohmann::json out;
  std::ostringstream md;

  // The scored render of view vi of `views` (the training views: at mid-exposure of its learned
  // trajectory), written as a PNG, against the view's sharp image.
  metrics::Scores score_view(const io::View& v, size_t vi, bool train, bool refine, const char* set) {
    const io::Image& gt = *v.sharp_mid;
    if (gt.width != v.camera.width || gt.height != v.camera.height)
      throw std::runtime_error("view '" + v.name + "': ground truth is " + std::to_string(gt.width) + "x" +
                               std::to_string(gt.height) + ", camera " + std::to_string(v.camera.width) + "x" +
                               std::to_string(v.camera.height));
    // Renders are sRGB (splat colours are); the ground truth is linear in memory.
    auto planar = io::planar_rgb(gt);
    const metrics::Image8 gt8 = metrics::encode_linear(planar, gt.width, gt.height, 3);
    for (float& x : planar) x = io::linear_to_srgb(x);
    gpu::Buffer target(ctx, planar.size() * 4, "gt");
    target.write(planar);
    Camera cam = train ? run.learned_camera(v, vi, 0.5) : v.camera;
    if (refine) {
      PoseRefineOptions ro;
      ro.iterations = refine_iters;
      ro.settings = s;
      cam = refine_pose(ctx, r, params, cam, target, ro).camera;
    }
    r.forward(params, cam, s, rs);
    const metrics::Image8 render8 =
        metrics::quantise_srgb(rs.outputs().rgb.read<float>(planar.size()), gt.width, gt.height, 3);
    metrics::write_png(run.dir / "eval" / set / (v.name + ".png"), render8);
    return metrics::score(render8, gt8);
  }

  void score(const std::vector<io::View>& views, const char* set, bool refine) {
    fs::create_directories(run.dir / "eval" / set);
    const bool train = &views == &data.train;
    nlohmann::json per = nlohmann::json::array();
    double sp = 0, ss = 0;
    int n = 0, reversed = 0;
    int motions = 0;  // views with a learned trajectory and ground truth
    double mid_error = 0;
    for (size_t vi = 0; vi < views.size(); ++vi) {
      if (!views[vi].sharp_mid) continue;
      const metrics::Scores val = score_view(views[vi], vi, train, refine, set);
      per.push_back({{"view", views[vi].name}, {"psnr", val.psnr}, {"ssim", val.ssim}});
      if (train) per.back()["motion"] = motion_json(run, data, vi, reversed, mid_error);
      motions += !per.back().value("motion", nlohmann::json()).is_null();
      sp += val.psnr;
      ss += val.ssim;
      ++n;
    }
    if (!n) return;
    out[set] = {{"views", per}, {"mean_psnr", sp / n}, {"mean_ssim", ss / n}};
    char line[160];
    std::snprintf(line, sizeof line, "| %s | %d | %.2f | %.4f |\n", set, n, sp / n, ss / n);
    md << line;
    std::printf("%-8s %3d views  PSNR %.2f dB  SSIM %.4f\n", set, n, sp / n, ss / n);
    if (!motions) return;
    out[set]["reversed_views"] = reversed;
    out[set]["mean_mid_error_px"] = mid_error / motions;
    std::printf("         %d of %d learned exposures run against the true motion\n", reversed, motions);
    std::printf("         learned mid-exposure cameras %.2f px from the true ones (mean)\n", mid_error / motions);
  }
};

static void write_text(const fs::path& path, const std::string& text) {
  io::write_file_atomic(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << text;
    io::close_or_throw(f, path);
  });
}

static int run_eval(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf(
        "usage: evflow eval RUN [--data DIR] [--refine-iters N] [--device N|name]\n"
        "  Renders every training view (deblur score, vs the sharp mid-exposure image) and every novel view,\n"
        "  and writes PSNR/SSIM per view and mean to RUN/eval.json and RUN/eval.md, scored on 8-bit sRGB\n"
        "  images as a saved PNG holds them; the scored renders go to RUN/eval/<set>/<view>.png.\n"
        "  Novel views are scored at the given poses ('novel') and after N Adam steps of test-pose\n"
        "  refinement with the Gaussians frozen ('novel_refined'; default N = 60, 0 skips it).\n"
        "  Runs with ldi=on also score the LDI network's own mid-exposure frame of every training view\n"
        "  ('ldi', frames in RUN/eval/ldi/).\n");
    return 0;
  }
  std::string data_override = p.value("--data");
  const uint32_t refine_iters = uint32_t(p.integer("--refine-iters", 60, 0, 1000000));
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  auto pos = p.positional();
  if (pos.size() != 1) throw std::invalid_argument("usage: evflow eval RUN");
  RunFolder run = RunFolder::open(pos[0]);
  io::Dataset data = io::load_dataset(data_override.empty() ? run.data_dir() : data_override);
  TrainConfig cfg;
  cfg.apply_json([&] {
    auto c = run.config;
    c.erase("data");
    return c;
  }());
  const auto& trajs = run.checkpoint.trajectories;
  if (!trajs.empty() && trajs.size() != data.train.size())
    throw std::runtime_error("checkpoint has " + std::to_string(trajs.size()) + " trajectories for " +
                             std::to_string(data.train.size()) + " training views");
  gpu::Context ctx(o);
  GaussianBuffers params(ctx, run.checkpoint.cloud.size(), run.checkpoint.cloud.sh_degree, "p_");
  params.upload(run.checkpoint.cloud);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  Scorer sc{ctx, run, data, params, r, rs, {}, refine_iters, {}, {}};
  sc.s.background = cfg.background;
  sc.s.antialiased = cfg.antialiased;
  sc.md << "| set | views | PSNR | SSIM |\n|---|---|---|---|\n";
  sc.score(data.train, "deblur", false);
  sc.score(data.novel, "novel", false);
  if (refine_iters > 0) sc.score(data.novel, "novel_refined", true);
  if (nlohmann::json ldi = score_ldi_frames(ctx, run, data, cfg); !ldi.is_null()) {
    char line[160];
    std::snprintf(line, sizeof line, "| ldi (the LDI's mid-exposure frames) | %zu | %.2f | %.4f |\n",
                  ldi["views"].size(), ldi["mean_psnr"].get<double>(), ldi["mean_ssim"].get<double>());
    sc.md << line;
    sc.out["ldi"] = std::move(ldi);
  }
  if (sc.out.empty()) throw std::runtime_error("the dataset has no sharp ground-truth images to evaluate against");
  sc.out["scored_on"] = "8-bit sRGB; SSIM: 11x11 Gaussian window, sigma 1.5, valid region, channel mean";
  sc.out["step"] = run.checkpoint.step;
  sc.out["gaussians"] = run.checkpoint.cloud.size();
  write_text(run.dir / "eval.json", sc.out.dump(2) + "\n");
  write_text(run.dir / "eval.md", sc.md.str());
  return 0;
}

static Command reg("eval", "score a training run against the sharp ground truth (eval.json, eval.md)", run_eval);

}  // namespace evflow::app
