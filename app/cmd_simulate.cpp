// evflow simulate: render a blurry multi-view dataset with events and ground truth (engine/sim).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include <unistd.h>

#include "cli.h"
#include "gpu/context.h"
#include "io/atomic_file.h"
#include "io/npy.h"
#include "sim/builtin_scenes.h"
#include "sim/gltf_scene.h"
#include "sim/simulation_writer.h"
#include "sim/simulator.h"

namespace evflow::app {

static const char* kSimulateHelp =
    "usage: evflow simulate [options]\n"
    "Renders a scene (glTF 2.0 or the built-in default) from a camera rig with shaken exposures and\n"
    "writes a dataset in our layout (docs/datasets.md) plus ground truth (docs/simulator.md).\n\n"
    "  --out DIR                 output folder (default: sim_dataset)\n"
    "  --scene FILE|NAME         .gltf/.glb scene, or a built-in scene: {scenes}\n"
    "                            (default: default)\n"
    "  --subdivide K             split every triangle into K x K (the same surfaces as a heavier mesh)\n"
    "  --write-scene F           write the scene (after --subdivide) as glTF (.glb or .gltf) and exit\n"
    "  --width N --height N      image and sensor size (default: 346 x 260)\n"
    "  --fov DEG                 vertical field of view (default: 50)\n"
    "  --train-views N           blurry training views (default: 16)\n"
    "  --novel-views N           sharp novel (test) views (default: 8)\n"
    "  --arc DEG                 angular span of the training cameras (default: 50)\n"
    "  --blur-px PX              target mean pixel path length per exposure (default: 12)\n"
    "  --exposure S              exposure time per training view, seconds (default: 0.04)\n"
    "  --view-spacing S          time between training exposures' starts (default: 0.1)\n"
    "  --translation-share X     translation shake per unit rotation x viewing distance (default: 0.3)\n"
    "  --shake smooth|jerk       the shake's sinusoids alone, or plus a sudden change of velocity per\n"
    "                            degree of freedom inside each exposure (default: smooth)\n"
    "  --max-step-px PX          bound on any pixel's motion between sub-frames (default: 0.5)\n"
    "  --max-subframes N         per-view sub-frame limit (default: 2000)\n"
    "  --pose-noise-rot DEG      std dev of rotation noise on the recorded poses (default: 0)\n"
    "  --pose-noise-trans X      std dev of translation noise on the recorded poses (default: 0)\n"
    "  --seed N                  random seed (default: 1)\n"
    "  --events PRESET           event model: default | noisy | ideal (default: default)\n"
    "  --theta-pos X --theta-neg X --theta-sigma X   thresholds (default: preset's, 0.2 0.2 0.03)\n"
    "  --cfa                     colour events through an RGGB filter array (default: luminance events)\n"
    "  --refractory S --shot-rate HZ --leak-rate HZ --jitter S   (default: preset's, 5e-4 0 0 0)\n"
    "  --ambient X               ambient light fraction (default: 0.35)\n"
    "  --texture-samples N       1 or 4 texture rays per pixel (default: 4)\n"
    "  --flow mid|all            ground-truth flow written: the interval at mid-exposure per view,\n"
    "                            or every sub-frame interval gt/flow/<view>_<k>.npy (large) (default: mid)\n"
    "  --device N|name           Vulkan device (default: automatic)\n"
    "  --verbose                 per-view statistics\n";

// Progress while the training views are simulated: on a terminal one line rewritten at every
// sub-frame interval (view, interval, ETA), else a line per finished view. The ETA assumes the
// views left take the mean time of those done (their sub-frame counts are chosen as they run).
class SimProgress {
 public:
  explicit SimProgress(int views) : views_(views), tty_(isatty(fileno(stdout))) {}
  void interval(const sim::Interval& iv) {
    if (iv.view != view_) {
      if (view_ >= 0) view_done();
      view_ = iv.view;
    }
    intervals_ = iv.index + 1;
    if (!tty_) return;
    std::printf("\r  view %d/%d  sub-frame interval %d  ETA %s ", iv.view + 1, views_, intervals_,
                eta(iv.view).c_str());
    std::fflush(stdout);
  }
  void end() {
    if (view_ >= 0) view_done();
    view_ = -1;
  }

 private:
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  std::string eta(int views_done) const {
    if (views_done == 0) return "-";
    char b[32];
    std::snprintf(b, sizeof b, "%.0fs", elapsed() / views_done * (views_ - views_done));
    return b;
  }
  void view_done() {
    if (tty_) std::printf("\r%60s\r", "");
    std::printf("  view %d/%d simulated (%d sub-frame intervals), %.1f s so far, ETA %s\n", view_ + 1, views_,
                intervals_, elapsed(), eta(view_ + 1).c_str());
    std::fflush(stdout);
  }
  const int views_;
  const bool tty_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  int view_ = -1, intervals_ = 0;
};

static int run_simulate(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::string help = kSimulateHelp;
    help.replace(help.find("{scenes}"), 8, join(sim::builtin_scene_names(), ", "));
    std::printf("%s", help.c_str());
    return 0;
  }
  sim::SimParams sp;
  const std::string out = p.value("--out", "sim_dataset");
  const std::string scene_path = p.value("--scene");
  const long long subdivide = p.integer("--subdivide", 1, 1, 1024);
  const std::string write_scene = p.value("--write-scene");
  const ImageSize size = p.image_size({sp.width, sp.height});
  sp.width = size.width;
  sp.height = size.height;
  sp.fov_y_deg = p.number("--fov", sp.fov_y_deg);
  sp.train_views = int(p.integer("--train-views", sp.train_views, 1, 100000));
  sp.novel_views = int(p.integer("--novel-views", sp.novel_views, 0, 100000));
  sp.arc_deg = p.number("--arc", sp.arc_deg);
  sp.blur_px = p.number("--blur-px", sp.blur_px);
  sp.exposure_s = p.number("--exposure", sp.exposure_s);
  sp.view_spacing_s = p.number("--view-spacing", sp.view_spacing_s);
  sp.translation_share = p.number("--translation-share", sp.translation_share);
  sp.shake = p.value("--shake", sp.shake);
  sp.max_step_px = p.number("--max-step-px", sp.max_step_px);
  sp.plan_step_px = std::min(sp.plan_step_px, 0.8 * sp.max_step_px);
  sp.max_subframes = int(p.integer("--max-subframes", sp.max_subframes, 1, 1000000));
  sp.pose_noise_rot_deg = p.number("--pose-noise-rot", 0);
  sp.pose_noise_trans = p.number("--pose-noise-trans", 0);
  sp.seed = uint64_t(p.integer("--seed", 1));
  const std::string preset = p.value("--events", "default");
  if (preset == "default")
    sp.events = events::EventModelParams::defaults();
  else if (preset == "noisy")
    sp.events = events::EventModelParams::noisy();
  else if (preset == "ideal")
    sp.events = events::EventModelParams::ideal();
  else
    throw std::invalid_argument("--events must be default, noisy or ideal");
  if (p.flag("--cfa")) sp.events.color = events::ColorMode::RGGB;
  sp.events.theta_pos = p.number("--theta-pos", sp.events.theta_pos);
  sp.events.theta_neg = p.number("--theta-neg", sp.events.theta_neg);
  sp.events.theta_sigma = p.number("--theta-sigma", sp.events.theta_sigma);
  sp.events.refractory_s = p.number("--refractory", sp.events.refractory_s);
  sp.events.shot_rate_hz = p.number("--shot-rate", sp.events.shot_rate_hz);
  sp.events.leak_rate_hz = p.number("--leak-rate", sp.events.leak_rate_hz);
  sp.events.jitter_s = p.number("--jitter", sp.events.jitter_s);
  sp.events.seed = sp.seed;
  sp.shading.ambient = float(p.number("--ambient", sp.shading.ambient));
  sp.shading.texture_samples = int(p.integer("--texture-samples", sp.shading.texture_samples, 1, 4));
  if (sp.shading.texture_samples != 1 && sp.shading.texture_samples != 4)
    throw std::invalid_argument("--texture-samples must be 1 or 4, got " + std::to_string(sp.shading.texture_samples));
  const std::string flow = p.value("--flow", "mid");
  if (flow != "mid" && flow != "all") throw std::invalid_argument("--flow must be mid or all");
  gpu::ContextOptions o = context_options(p);
  const bool verbose = p.flag("--verbose");
  p.reject_unknown();
  if (!p.positional().empty()) throw std::invalid_argument("unexpected argument '" + p.positional()[0] + "'");

  const auto start = std::chrono::steady_clock::now();
  sim::Scene scene = sim::builtin_or_gltf_scene(scene_path);
  if (subdivide > 1) scene = sim::subdivide(scene, int(subdivide));
  if (!write_scene.empty()) {
    sim::write_gltf(scene, write_scene);
    std::printf("wrote scene %s (%zu triangles) to %s\n", scene.source.c_str(), scene.triangle_count(),
                write_scene.c_str());
    return 0;
  }
  gpu::Context ctx(o);
  std::printf("simulate: scene %s (%zu triangles, %zu textures), %ux%u, %d training + %d novel views, device %s\n",
              scene.source.c_str(), scene.triangle_count(), scene.textures.size(), sp.width, sp.height, sp.train_views,
              sp.novel_views, ctx.caps().name.c_str());
  sim::Simulator simulator(ctx, scene, sp);
  const std::filesystem::path dir(out);
  sim::SimResult res;
  // Written into a fresh folder that replaces DIR at the end: a failure leaves the old DIR whole.
  io::write_folder_atomic(dir, "dataset.json", [&](const std::filesystem::path& stage) {
    if (flow == "all") std::filesystem::create_directories(stage / "gt" / "flow");
    SimProgress progress(sp.train_views);
    sim::IntervalCallback cb = [&](const sim::Interval& iv) {
      if (flow == "all") {
        char name[64];
        std::snprintf(name, sizeof name, "%03d_%04d.npy", iv.view, iv.index);
        io::write_npy<float>(stage / "gt" / "flow" / name, {sp.height, sp.width, 2}, iv.flow);
      }
      progress.interval(iv);
    };
    res = simulator.run(cb, verbose);
    progress.end();
    res.scene_source = scene.source;
    res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    sim::write_simulation(res, stage);
  });
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "simulate: wrote %s\n  time %.1f s (simulation %.1f s), %zu events, %zu sub-frames, mean blur %.2f px, "
      "max sub-frame step %.3f px\n  vs the sharp frames, 8-bit sRGB: EDI (nominal thresholds) PSNR %.2f dB / SSIM "
      "%.4f, "
      "blurry %.2f dB / %.4f (gain %.2f dB)\n",
      out.c_str(), total, res.stats.seconds, res.stats.events, res.stats.subframes, res.stats.mean_blur_px,
      res.stats.max_step_px, res.stats.psnr_edi, res.stats.ssim_edi, res.stats.psnr_blurry, res.stats.ssim_blurry,
      res.stats.psnr_edi - res.stats.psnr_blurry);
  return 0;
}

static Command reg("simulate", "render a blurry event-camera dataset from a glTF scene (or the default scene)",
                   run_simulate);

}  // namespace evflow::app
