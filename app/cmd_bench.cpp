// evflow bench: stage timings (medians over repeated runs), as a table or JSON.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <vector>

#include <sys/resource.h>

#include "bench_conv.h"
#include "bench_kernels.h"
#include "bench_stats.h"
#include "cli.h"
#include "flow/flow_estimator.h"
#include "gpu/commands.h"
#include "io/camera_json.h"
#include "loss/event_loss.h"
#include "run_files.h"
#include "sim/builtin_scenes.h"
#include "sim/mesh_renderer.h"
#include "sim/simulator.h"
#include "splat/rasterizer.h"
#include "splat/synthetic.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"

namespace evflow::app {

// Named stage times in recording order, each the median of its runs, as JSON members.
static void print_stages_json(const std::vector<std::string>& order,
                              std::map<std::string, std::vector<double>>& stages) {
  for (size_t i = 0; i < order.size(); ++i)
    std::printf("%s\"%s\": %.3f", i ? ", " : "", order[i].c_str(), median(stages[order[i]]));
}

// Stage times (GPU timestamps) of repeated runs: each stage's samples in first-seen order, and
// each run's GPU total and wall time.
struct StageSamples {
  std::map<std::string, std::vector<double>> stages;
  std::vector<std::string> order;
  std::vector<double> totals, walls;
  void add(const std::vector<std::pair<std::string, double>>& stage_ms, double wall) {
    double total = 0;
    for (auto& [name, ms] : stage_ms) {
      if (!stages.count(name)) order.push_back(name);
      stages[name].push_back(ms);
      total += ms;
    }
    totals.push_back(total);
    walls.push_back(wall);
  }
};

// A run's first training view at mid-exposure, as `evflow eval` renders it (its learned camera),
// from the run's dataset.
static Camera run_camera(const RunFolder& run) {
  const std::string data_dir = run.data_dir();
  try {
    const io::Dataset data = io::load_dataset(data_dir);
    return run.learned_camera(data.train.at(0), 0, 0.5);
  } catch (const std::exception& e) {
    throw std::runtime_error(run.dir.string() + ": its dataset '" + data_dir + "' gives no camera (" + e.what() +
                             "); name one with --camera");
  }
}

// The bench scene: the first camera of --camera (its size and intrinsics), else a run's first
// training view (--splats RUN), else a 60-degree camera of --width x --height; the splats of
// --splats (a run, .ply or .glb) or N synthetic Gaussians in front of that camera.
static std::pair<Camera, GaussianCloud> raster_scene(ArgParser& p) {
  const auto [W, H] = p.image_size({346, 260});
  const size_t N = size_t(p.integer("--gaussians", 100000, 1, 100000000));
  const int degree = int(p.integer("--sh-degree", 3));
  const std::string camera_file = p.value("--camera"), splats = p.value("--splats");
  std::optional<RunFolder> run;
  if (!splats.empty() && std::filesystem::is_directory(splats)) run = RunFolder::open(splats);
  const Camera cam = !camera_file.empty() ? io::read_cameras_json(camera_file).at(0)
                     : run                ? run_camera(*run)
                                          : Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 1}, {0, -1, 0});
  if (run) return {cam, std::move(run->checkpoint.cloud)};
  return {cam, splats.empty() ? synthetic_cloud(1, N, degree, cam) : load_splats(splats)};
}

static int bench_raster(ArgParser& p) {
  const auto [cam, cloud] = raster_scene(p);
  const uint32_t W = cam.width, H = cam.height;
  const size_t N = cloud.size();
  const int degree = cloud.sh_degree;
  const int repeats = int(p.integer("--repeats", 10, 1, 100000));
  const int warmup = int(p.integer("--warmup", 2, 0, 100000));
  const bool json = p.flag("--json");
  const bool aa = p.flag("--antialiased");
  gpu::ContextOptions o = context_options(p);
  o.kernel_times = p.flag("--kernels");
  p.reject_unknown();
  gpu::Context ctx(o);
  GaussianBuffers params(ctx, N, degree, "p_"), grads(ctx, N, degree, "v_");
  params.upload(cloud);
  const size_t hw = size_t(W) * H;
  gpu::Buffer v_rgb(ctx, hw * 12, "v_rgb"), v_alpha(ctx, hw * 4, "v_alpha");
  std::vector<float> w(hw * 3);
  for (size_t i = 0; i < w.size(); ++i) w[i] = float((i * 2654435761u) % 1000) / 1000.0f - 0.5f;
  v_rgb.write(w);
  w.resize(hw);
  v_alpha.write(w);
  RenderSettings s;
  s.antialiased = aa;
  Rasterizer r(ctx);
  RenderState rs(ctx);
  StageSamples samples;
  KernelSamples kernels;
  for (int it = 0; it < warmup + repeats; ++it) {
    auto t0 = std::chrono::steady_clock::now();
    r.forward(params, cam, s, rs);
    r.backward(rs, params, v_rgb, v_alpha, grads);
    double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::vector<std::pair<std::string, double>> kernel_times = ctx.take_kernel_times();
    if (it < warmup) continue;
    samples.add(r.stage_ms(), wall);
    if (o.kernel_times) kernels.add_run(kernel_times);
  }
  auto& [stages, order, totals, walls] = samples;
  if (json) {
    std::printf(
        "{\"bench\": \"raster\", \"device\": \"%s\", \"width\": %u, \"height\": %u, \"gaussians\": %zu, "
        "\"sh_degree\": %d, \"intersections\": %u, \"repeats\": %d, \"stages_ms\": {",
        ctx.caps().name.c_str(), W, H, N, degree, rs.num_intersections(), repeats);
    print_stages_json(order, stages);
    // Minima too: on a machine shared with other work the fastest repeat is the least disturbed.
    std::printf("}, \"stages_min_ms\": {");
    for (size_t i = 0; i < order.size(); ++i)
      std::printf("%s\"%s\": %.3f", i ? ", " : "", order[i].c_str(),
                  *std::min_element(stages[order[i]].begin(), stages[order[i]].end()));
    std::printf("}, \"gpu_total_ms\": %.3f, \"gpu_total_min_ms\": %.3f, \"wall_ms\": %.3f", median(totals),
                *std::min_element(totals.begin(), totals.end()), median(walls));
    if (o.kernel_times) {
      std::printf(", ");
      kernels.print_json();
    }
    std::printf("}\n");
  } else {
    std::printf("raster bench on %s: %ux%u, %zu Gaussians (SH %d), %u intersections, median of %d\n",
                ctx.caps().name.c_str(), W, H, N, degree, rs.num_intersections(), repeats);
    for (auto& name : order) std::printf("  %-20s %9.2f ms\n", name.c_str(), median(stages[name]));
    std::printf("  %-20s %9.2f ms\n  %-20s %9.2f ms\n", "total (GPU)", median(totals), "wall (with host)",
                median(walls));
    if (o.kernel_times) kernels.print_text();
  }
  return 0;
}

// The process's largest resident set so far (MiB). On a CPU driver it holds the device's buffers too.
static double peak_host_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;  // KiB on Linux
}

// The state a train bench starts from with --splats: the splats of a run, .ply or .glb (a run's
// learned exposure trajectories too, in blur mode), at step 0 with a fresh optimizer.
static Checkpoint bench_start(const std::string& splats, const TrainConfig& cfg) {
  Checkpoint start;
  if (std::filesystem::is_directory(splats)) {
    start = RunFolder::open(splats).checkpoint;
    start.step = 0;
    start.optimizer.clear();
    if (cfg.mode != TrainMode::Blur) start.trajectories.clear();
  } else {
    start.cloud = load_splats(splats);
  }
  return start;
}

// Named stage times in recording order, each the median of its runs, as one line of text.
static void print_stages_text(const char* title, const std::vector<std::string>& order,
                              std::map<std::string, std::vector<double>>& stages) {
  std::printf("  %s:", title);
  for (auto& name : order) std::printf(" %s %.1f,", name.c_str(), median(stages[name]));
  std::printf(" ms\n");
}

// How many times the trainer's event terms have counted a view's events (each view's counts are
// kept for its next steps, so a run's steady state counts none).
static uint64_t event_count_passes(const Trainer& t) {
  uint64_t n = 0;
  for (const LossTerm* term : t.losses())
    if (const auto* e = dynamic_cast<const EventLoss*>(term)) n += e->count_passes();
  return n;
}

// Training steps (sharp views rendered from a synthetic ground-truth cloud, or a dataset folder
// with any method): it/s and the split between rasterization, loss terms and optimizer.
static int bench_train(ArgParser& p) {
  auto [W, H] = p.image_size({346, 260});
  const uint32_t N = uint32_t(p.integer("--gaussians", 100000, 1, 100000000));
  const int steps = int(p.integer("--steps", 20, 1, 1000000));
  const int warmup = int(p.integer("--warmup", 1, 0, 1000000));
  const int views = int(p.integer("--views", 8, 1, 100000));
  const bool json = p.flag("--json");
  const std::string data_dir = p.value("--data"), splats = p.value("--splats");
  std::string method = p.value("--method");
  if (method.empty()) method = "plain";
  gpu::ContextOptions o = context_options(p);
  o.kernel_times = p.flag("--kernels");
  p.reject_unknown();
  std::vector<std::pair<std::string, std::string>> overrides;  // training keys, as for evflow train
  for (auto& kv : p.positional()) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos) throw std::invalid_argument("bench train: unexpected argument '" + kv + "'");
    overrides.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
  }
  gpu::Context ctx(o);
  // A dataset folder (blurry views + events: every method), or sharp views rendered from a
  // synthetic cloud (plain only: it has no exposures or events).
  io::Dataset data =
      data_dir.empty() ? render_synthetic_dataset(ctx, W, H, views, 0, 20000) : io::load_dataset(data_dir);
  W = data.train.at(0).camera.width, H = data.train.at(0).camera.height;
  TrainConfig cfg;
  cfg.apply_method(method);
  if (data_dir.empty() && method != "plain")
    throw std::invalid_argument("bench train: --method " + method + " needs --data DIR");
  cfg.init_gaussians = N;
  cfg.densify = false;       // a fixed count: the steps are comparable
  cfg.event_from = 0;        // the event term (when the method has one) is on in every timed step
  cfg.event_flip_until = 1;  // and so is the direction check
  for (auto& [k, v] : overrides) cfg.set(k, v);
  cfg.iterations =
      std::max<uint32_t>(cfg.iterations, uint32_t(warmup + steps));  // the warm-up steps and the timed ones
  Trainer t = splats.empty() ? Trainer(ctx, data, cfg) : Trainer(ctx, data, cfg, bench_start(splats, cfg));
  // Untimed: pipelines compiled, buffers sized; as many steps as views visit each view once, so
  // that the timed steps find every view's event counts kept (the steady state of a run).
  for (int i = 0; i < warmup; ++i) t.step();
  ctx.take_kernel_times();  // the warm-up's
  KernelSamples kernels;
  std::vector<double> total, fwd, loss, bwd, opt, ldi;
  std::map<std::string, std::vector<double>> stages, loss_stages, ldi_stages;  // rasterizer, loss terms, LDI
  std::vector<std::string> order, loss_order, ldi_order;
  // A step's stages into per-stage samples; a stage recorded several times a step (chunks) adds up.
  auto add_step = [](const std::vector<std::pair<std::string, double>>& step_stages, std::vector<std::string>& names,
                     std::map<std::string, std::vector<double>>& samples) {
    std::map<std::string, double> sum;
    for (auto& [name, ms] : step_stages) {
      if (!samples.count(name) && !sum.count(name)) names.push_back(name);
      sum[name] += ms;
    }
    for (auto& [name, ms] : sum) samples[name].push_back(ms);
  };
  const uint64_t submits0 = ctx.submits(), transfers0 = ctx.transfers(), counts0 = event_count_passes(t);
  for (int i = 0; i < steps; ++i) {
    StepStats st = t.step();
    if (o.kernel_times) kernels.add_run(ctx.take_kernel_times());
    for (auto& [name, ms] : t.rasterizer().stage_ms()) {
      if (!stages.count(name)) order.push_back(name);
      stages[name].push_back(ms);
    }
    add_step(st.loss_stages, loss_order, loss_stages);
    add_step(st.ldi_stages, ldi_order, ldi_stages);
    total.push_back(st.ms);
    fwd.push_back(st.raster_forward_ms);
    loss.push_back(st.loss_ms);
    bwd.push_back(st.raster_backward_ms);
    opt.push_back(st.optimizer_ms);
    ldi.push_back(st.ldi_ms);
  }
  const uint32_t count = uint32_t(t.params().count);
  const double m = median(total);
  const double submits = double(ctx.submits() - submits0) / steps,
               transfers = double(ctx.transfers() - transfers0) / steps,
               counts = double(event_count_passes(t) - counts0) / steps;
  const double host_mib = peak_host_mib(), device_mib = double(ctx.peak_device_bytes()) / (1 << 20);
  if (json) {
    std::printf(
        "{\"bench\": \"train\", \"method\": \"%s\", \"device\": \"%s\", \"width\": %u, \"height\": %u, \"gaussians\": "
        "%u, \"steps\": %d, \"warmup\": %d, \"peak_host_mib\": %.1f, \"peak_device_mib\": %.1f, \"submits_per_step\": "
        "%.1f, "
        "\"transfers_per_step\": %.1f, \"event_counts_per_step\": %.2f, \"it_per_s\": %.3f, \"ms\": "
        "{\"rasterize_forward\": %.2f, \"loss\": %.2f, "
        "\"rasterize_backward\": %.2f, "
        "\"optimizer\": %.2f, \"ldi\": %.2f, \"step\": %.2f}, \"raster_stages_ms\": {",
        method.c_str(), ctx.caps().name.c_str(), W, H, count, steps, warmup, host_mib, device_mib, submits, transfers,
        counts, 1000.0 / m, median(fwd), median(loss), median(bwd), median(opt), median(ldi), m);
    print_stages_json(order, stages);
    std::printf("}, \"loss_stages_ms\": {");
    print_stages_json(loss_order, loss_stages);
    std::printf("}, \"ldi_stages_ms\": {");
    print_stages_json(ldi_order, ldi_stages);
    std::printf("}");
    if (o.kernel_times) {
      std::printf(", ");
      kernels.print_json();
    }
    std::printf("}\n");
  } else {
    std::printf("train bench (%s) on %s: %ux%u, %u Gaussians, one view per step, median of %d steps after %d untimed\n",
                method.c_str(), ctx.caps().name.c_str(), W, H, count, steps, warmup);
    std::printf(
        "  rasterize forward   %9.2f ms\n  loss terms          %9.2f ms\n  rasterize backward  %9.2f ms\n"
        "  optimizer (Adam)    %9.2f ms\n  LDI branch          %9.2f ms\n  step                %9.2f ms  (%.2f it/s)\n",
        median(fwd), median(loss), median(bwd), median(opt), median(ldi), m, 1000.0 / m);
    print_stages_text("rasterizer stages", order, stages);
    print_stages_text("loss term stages", loss_order, loss_stages);
    if (!ldi_order.empty()) print_stages_text("LDI branch stages", ldi_order, ldi_stages);
    std::printf("  peak memory: host %.1f MiB (the process's resident set), device %.1f MiB (buffers)\n", host_mib,
                device_mib);
    std::printf("  round trips per step: %.1f submits, %.1f host-device copies; %.2f event counting passes\n", submits,
                transfers, counts);
    if (o.kernel_times) kernels.print_text();
  }
  return 0;
}

// Flow estimation of the training views of a dataset: wall seconds and the GPU stages' totals.
static int bench_flow(ArgParser& p) {
  const std::string data_dir = p.value("--data");
  const int views = int(p.integer("--views", 0, 0, 100000));  // 0: all
  const bool json = p.flag("--json");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  if (data_dir.empty()) throw std::invalid_argument("bench flow: --data DIR needed (a dataset with events)");
  const io::Dataset data = io::load_dataset(data_dir);
  if (data.events.size() == 0) throw std::invalid_argument("bench flow: " + data_dir + " has no event stream");
  gpu::Context ctx(o);
  flow::FlowEstimator est(ctx);
  std::vector<double> u;
  const uint32_t frames = 2 * TrainConfig{}.virtual_frames + 1;
  for (uint32_t i = 0; i < frames; ++i) u.push_back(double(i) / (frames - 1));
  const size_t n = views > 0 ? std::min<size_t>(size_t(views), data.train.size()) : data.train.size();
  const auto start = std::chrono::steady_clock::now();
  size_t events = 0;
  for (size_t v = 0; v < n; ++v) {
    const io::View& view = data.train[v];
    const flow::PixelEvents ev = flow::pixel_events(data.events, view.exposure_start, view.exposure_end, data_dir);
    events += ev.size();
    est.estimate(ev, u);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const uint32_t W = data.train[0].camera.width, H = data.train[0].camera.height;
  if (json) {
    std::printf(
        "{\"bench\": \"flow\", \"device\": \"%s\", \"width\": %u, \"height\": %u, \"views\": %zu, "
        "\"intervals\": %u, \"events\": %zu, \"evaluations\": %llu, \"seconds\": %.3f, \"stages_ms\": {",
        ctx.caps().name.c_str(), W, H, n, frames - 1, events, (unsigned long long)est.evaluations(), seconds);
    for (size_t i = 0; i < est.stage_ms().size(); ++i)
      std::printf("%s\"%s\": %.1f", i ? ", " : "", est.stage_ms()[i].first.c_str(), est.stage_ms()[i].second);
    std::printf("}}\n");
  } else {
    std::printf("flow bench on %s: %ux%u, %zu views x %u intervals, %zu events, %llu evaluations: %.2f s\n",
                ctx.caps().name.c_str(), W, H, n, frames - 1, events, (unsigned long long)est.evaluations(), seconds);
    std::printf("  GPU stages (total):");
    for (auto& [name, ms] : est.stage_ms()) std::printf(" %s %.0f,", name.c_str(), ms);
    std::printf(" ms\n");
  }
  return 0;
}

// The simulator's renderer on its own: each training view's mid-exposure camera of the rig, per
// stage (GPU timestamps), medians over every frame rendered.
static int bench_sim(ArgParser& p) {
  sim::SimParams sp;
  const ImageSize size = p.image_size({sp.width, sp.height});
  sp.width = size.width;
  sp.height = size.height;
  const std::string scene_arg = p.value("--scene");
  const long long subdivide = p.integer("--subdivide", 1, 1, 1024);
  const int repeats = int(p.integer("--repeats", 3, 1, 100000)), warmup = int(p.integer("--warmup", 1, 0, 100000));
  const bool json = p.flag("--json");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  sim::Scene scene = sim::builtin_or_gltf_scene(scene_arg);
  if (subdivide > 1) scene = sim::subdivide(scene, int(subdivide));
  gpu::Context ctx(o);
  const sim::Simulator rig(ctx, scene, sp);  // its cameras
  sim::MeshRenderer r(ctx, scene, sp.shading);
  StageSamples samples;
  for (int it = 0; it < warmup + repeats; ++it)
    for (int v = 0; v < sp.train_views; ++v) {
      const auto t0 = std::chrono::steady_clock::now();
      r.render(rig.shake_pose(v, 0.5, 1.0));
      const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (it >= warmup) samples.add(r.stage_ms(), wall);
    }
  auto& [stages, order, totals, walls] = samples;
  const size_t frames = totals.size();
  if (json) {
    std::printf(
        "{\"bench\": \"sim\", \"device\": \"%s\", \"scene\": \"%s\", \"triangles\": %zu, \"width\": %u, "
        "\"height\": %u, \"frames\": %zu, \"stages_ms\": {",
        ctx.caps().name.c_str(), scene.source.c_str(), scene.triangle_count(), sp.width, sp.height, frames);
    print_stages_json(order, stages);
    std::printf("}, \"gpu_total_ms\": %.3f, \"wall_ms\": %.3f}\n", median(totals), median(walls));
  } else {
    std::printf("sim bench on %s: scene %s (%zu triangles), %ux%u, median of %zu frames\n", ctx.caps().name.c_str(),
                scene.source.c_str(), scene.triangle_count(), sp.width, sp.height, frames);
    for (auto& name : order) std::printf("  %-22s %9.2f ms\n", name.c_str(), median(stages[name]));
    std::printf("  %-22s %9.2f ms\n  %-22s %9.2f ms\n", "total (GPU)", median(totals), "wall (with host)",
                median(walls));
  }
  return 0;
}

static int run_bench(const Args& a) {
  ArgParser p(a);
  auto pos = p.positional();
  if (p.flag("--help") || pos.empty()) {
    std::printf(
        "usage: evflow bench raster [--width 346] [--height 260] [--gaussians 100000] [--sh-degree 3]\n"
        "                           [--camera cams.json] [--splats RUN|F.ply|F.glb]\n"
        "                           [--repeats 10] [--warmup 2] [--antialiased] [--kernels] [--json]\n"
        "                           [--device N|name]\n"
        "  Times forward + backward of the splat rasterizer per stage (GPU timestamps, medians), on\n"
        "  synthetic Gaussians in front of a 60-degree camera, or from the first camera of a camera file\n"
        "  (as evflow render --camera reads; its size replaces --width/--height), of the given splats;\n"
        "  a run's splats without --camera: from its first training view at mid-exposure.\n"
        "       evflow bench train [--width 346] [--height 260] [--gaussians 100000] [--steps 20] [--warmup 1]\n"
        "                          [--views 8] [--kernels] [--json]\n"
        "                          [--data DIR --method plain|edi|blur-only|blur+events|blur+events+warp|\n"
        "                          blur+events+flow] [--splats RUN|F.ply|F.glb] [key=value ...]\n"
        "  Training steps (render, loss terms, backward, Adam): it/s and the split per part. With --data,\n"
        "  the steps train that dataset with the method (blur modes: 2N+1 renders per step). --splats\n"
        "  starts from those splats (a run's: its learned exposures too) instead of --gaussians new ones.\n"
        "  --warmup: untimed steps first; with --data, one per training view times a run's steady state\n"
        "  (every view's event counts kept).\n"
        "  --kernels (raster, train): also each kernel's GPU time per repeat or step (a timestamp after\n"
        "  every dispatch; medians, slowest first) and its dispatches.\n"
        "       evflow bench flow --data DIR [--views N] [--json]\n"
        "  Optical flow from events of the first N (default all) training views: seconds in all and\n"
        "  the GPU stages summed over every evaluation of the contrast.\n"
        "       evflow bench conv [--width 346] [--height 260] [--batch 1] [--widths 32,64,128,64,16,1]\n"
        "                         [--repeats 5] [--json]\n"
        "  Forward and backward of a stack of 3x3 convolutions with ReLU between (the LDI network's\n"
        "  layers; --widths: input channels, then each layer's) over a batch of images, one dispatch\n"
        "  per layer: ms and GFLOP/s per layer.\n"
        "       evflow bench sim [--scene NAME|F.glb] [--subdivide K] [--width 346] [--height 260]\n"
        "                        [--repeats 3] [--warmup 1] [--json]\n"
        "  The simulator's mesh renderer per stage (GPU timestamps, medians over frames) at the\n"
        "  mid-exposure camera of each training view of the rig (--subdivide: as evflow simulate).\n");
    return pos.empty() ? 2 : 0;
  }
  p.args.erase(std::find(p.args.begin(), p.args.end(), pos[0]));
  if (pos[0] == "raster") return bench_raster(p);
  if (pos[0] == "train") return bench_train(p);
  if (pos[0] == "flow") return bench_flow(p);
  if (pos[0] == "conv") return bench_conv(p);
  if (pos[0] == "sim") return bench_sim(p);
  throw std::invalid_argument("unknown benchmark '" + pos[0] + "' (available: raster, train, flow, conv, sim)");
}

static Command reg("bench", "time the stages of a pipeline (raster, train, flow, conv, sim), as a table or JSON",
                   run_bench);

}  // namespace evflow::app
