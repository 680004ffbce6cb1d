// evflow bench: stage timings (medians over repeated runs), as a table or JSON.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <vector>

#include "cli.h"
#include "gpu/commands.h"
#include "splat/rasterizer.h"
#include "splat/synthetic.h"

namespace evflow::app {

static double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

static int bench_raster(ArgParser& p) {
  const uint32_t W = uint32_t(p.integer("--width", 346)), H = uint32_t(p.integer("--height", 260));
  const size_t N = size_t(p.integer("--gaussians", 100000));
  const int degree = int(p.integer("--sh-degree", 3));
  const int repeats = int(p.integer("--repeats", 10));
  const int warmup = int(p.integer("--warmup", 2));
  const bool json = p.flag("--json");
  const bool aa = p.flag("--antialiased");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  gpu::Context ctx(o);
  Camera cam = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 1}, {0, -1, 0});
  GaussianCloud cloud = synthetic_cloud(1, N, degree, cam);
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
  std::map<std::string, std::vector<double>> stages;
  std::vector<std::string> order;
  std::vector<double> totals, walls;
  for (int it = 0; it < warmup + repeats; ++it) {
    auto t0 = std::chrono::steady_clock::now();
    r.forward(params, cam, s);
    r.backward(params, v_rgb, v_alpha, grads);
    double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (it < warmup) continue;
    double total = 0;
    for (auto& [name, ms] : r.stage_ms()) {
      if (!stages.count(name)) order.push_back(name);
      stages[name].push_back(ms);
      total += ms;
    }
    totals.push_back(total);
    walls.push_back(wall);
  }
  if (json) {
    std::printf("{\"bench\": \"raster\", \"device\": \"%s\", \"width\": %u, \"height\": %u, \"gaussians\": %zu, "
                "\"sh_degree\": %d, \"intersections\": %u, \"repeats\": %d, \"stages_ms\": {",
                ctx.caps().name.c_str(), W, H, N, degree, r.num_intersections(), repeats);
    for (size_t i = 0; i < order.size(); ++i)
      std::printf("%s\"%s\": %.3f", i ? ", " : "", order[i].c_str(), median(stages[order[i]]));
    std::printf("}, \"gpu_total_ms\": %.3f, \"wall_ms\": %.3f}\n", median(totals), median(walls));
  } else {
    std::printf("raster bench on %s: %ux%u, %zu Gaussians (SH %d), %u intersections, median of %d\n",
                ctx.caps().name.c_str(), W, H, N, degree, r.num_intersections(), repeats);
    for (auto& name : order) std::printf("  %-20s %9.2f ms\n", name.c_str(), median(stages[name]));
    std::printf("  %-20s %9.2f ms\n  %-20s %9.2f ms\n", "total (GPU)", median(totals), "wall (with host)", median(walls));
  }
  return 0;
}

static int run_bench(const Args& a) {
  ArgParser p(a);
  auto pos = p.positional();
  if (p.flag("--help") || pos.empty()) {
    std::printf("usage: evflow bench raster [--width 346] [--height 260] [--gaussians 100000] [--sh-degree 3]\n"
                "                           [--repeats 10] [--warmup 2] [--antialiased] [--json] [--device N|name]\n"
                "  Times forward + backward of the splat rasterizer per stage (GPU timestamps, medians).\n");
    return pos.empty() ? 2 : 0;
  }
  p.args.erase(std::find(p.args.begin(), p.args.end(), pos[0]));
  if (pos[0] == "raster") return bench_raster(p);
  throw std::invalid_argument("unknown benchmark '" + pos[0] + "' (available: raster)");
}

static Command reg("bench", "time the stages of a pipeline (raster), as a table or JSON", run_bench);

}  // namespace evflow::app
