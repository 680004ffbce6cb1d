#include "bench_conv.h"

#include <cstdio>
#include <ctime>
#include <map>
#include <sstream>
#include <stdexcept>

#include "bench_stats.h"
#include "gpu/commands.h"
#include "nn/conv_stack.h"

namespace evflow::app {

namespace {

std::vector<uint32_t> parse_widths(const std::string& s) {
  std::vector<uint32_t> w;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    const long v = std::strtol(item.c_str(), nullptr, 10);
    if (v <= 0 || v > 4096) throw std::invalid_argument("bench conv: --widths: '" + item + "' is not a width");
    w.push_back(uint32_t(v));
  }
  if (w.size() < 2) throw std::invalid_argument("bench conv: --widths needs the input width and at least one layer");
  return w;
}

struct LayerTimes {
  std::vector<double> fwd, bwd;
};
struct Timing {
  std::vector<LayerTimes> layers;
  double cpu_s = 0;  // the process's CPU seconds per repeat (all of lavapipe's threads)
};

// Forward and backward, timed per layer by GPU timestamps; the CPU time of the timed repeats
// too, which another job on the machine does not inflate as it does the wall time.
Timing run_repeats(gpu::Context& ctx, nn::ConvStack& stack, int warmup, int repeats) {
  gpu::Commands cmd(ctx);
  Timing t;
  t.layers.resize(stack.layers());
  std::clock_t start = 0;
  for (int it = 0; it < warmup + repeats; ++it) {
    if (it == warmup) start = std::clock();
    stack.forward(cmd, "forward");
    stack.backward(cmd, false, false, "backward");
    cmd.submit();
    if (it < warmup) continue;
    for (auto& [name, ms] : cmd.stage_ms()) {
      const size_t layer = std::stoul(name.substr(name.find(' ') + 1));
      (name[0] == 'f' ? t.layers[layer].fwd : t.layers[layer].bwd).push_back(ms);
    }
  }
  t.cpu_s = double(std::clock() - start) / CLOCKS_PER_SEC / repeats;
  return t;
}

// One row per layer and the totals: milliseconds and FLOP (2 per MAC). The backward does the
// weight gradient, and the input gradient for every layer but the first (the stack's input needs
// none): 2 or 1 times the forward's work.
struct Figures {
  double fwd_ms = 0, bwd_ms = 0, fwd_flop = 0, bwd_flop = 0;
  double fwd_gflops() const { return fwd_flop / fwd_ms * 1e-6; }
  double bwd_gflops() const { return bwd_flop / bwd_ms * 1e-6; }
  double gflops() const { return (fwd_flop + bwd_flop) / (fwd_ms + bwd_ms) * 1e-6; }
};

std::vector<Figures> layer_figures(const std::vector<uint64_t>& macs, const Timing& timing, Figures& total) {
  std::vector<Figures> rows;
  for (size_t i = 0; i < timing.layers.size(); ++i) {
    const double flop = 2.0 * macs[i];
    rows.push_back({median(timing.layers[i].fwd), median(timing.layers[i].bwd), flop, flop * (i ? 2 : 1)});
    total.fwd_ms += rows.back().fwd_ms, total.bwd_ms += rows.back().bwd_ms;
    total.fwd_flop += rows.back().fwd_flop, total.bwd_flop += rows.back().bwd_flop;
  }
  return rows;
}

void print_table(const std::vector<uint64_t>& macs, const Timing& timing, const std::string& head) {
  std::printf("%s\n  layer   GMAC   fwd ms  fwd GFLOP/s   bwd ms  bwd GFLOP/s\n", head.c_str());
  Figures t;
  const std::vector<Figures> rows = layer_figures(macs, timing, t);
  for (size_t i = 0; i < rows.size(); ++i)
    std::printf("  %5zu %6.2f %8.1f %12.2f %8.1f %12.2f\n", i, macs[i] * 1e-9, rows[i].fwd_ms, rows[i].fwd_gflops(),
                rows[i].bwd_ms, rows[i].bwd_gflops());
  std::printf("  total  %6.2f %7.1f %12.2f %8.1f %12.2f\n", t.fwd_flop * 0.5e-9, t.fwd_ms, t.fwd_gflops(), t.bwd_ms,
              t.bwd_gflops());
  std::printf("  forward + backward: %.2f GFLOP/s; %.2f s of CPU per repeat, %.2f GFLOP per CPU second\n", t.gflops(),
              timing.cpu_s, (t.fwd_flop + t.bwd_flop) / timing.cpu_s * 1e-9);
}

void print_json(const std::vector<uint64_t>& macs, const Timing& timing, const std::string& head) {
  std::printf("%s, \"layers\": [", head.c_str());
  Figures t;
  const std::vector<Figures> rows = layer_figures(macs, timing, t);
  for (size_t i = 0; i < rows.size(); ++i)
    std::printf(
        "%s{\"macs\": %llu, \"forward_ms\": %.3f, \"forward_gflops\": %.6g, \"backward_ms\": %.3f, "
        "\"backward_gflops\": %.6g}",
        i ? ", " : "", (unsigned long long)macs[i], rows[i].fwd_ms, rows[i].fwd_gflops(), rows[i].bwd_ms,
        rows[i].bwd_gflops());
  std::printf(
      "], \"forward_ms\": %.3f, \"forward_gflops\": %.6g, \"backward_ms\": %.3f, \"backward_gflops\": %.6g, "
      "\"gflops\": %.6g, \"cpu_seconds\": %.3f, \"gflop_per_cpu_second\": %.6g}\n",
      t.fwd_ms, t.fwd_gflops(), t.bwd_ms, t.bwd_gflops(), t.gflops(), timing.cpu_s,
      (t.fwd_flop + t.bwd_flop) / timing.cpu_s * 1e-9);
}

}  // namespace

int bench_conv(ArgParser& p) {
  const auto [W, H] = p.image_size({346, 260});
  const std::vector<uint32_t> widths = parse_widths(p.value("--widths", "32,64,128,64,16,1"));
  const int repeats = int(p.integer("--repeats", 5, 1, 100000));
  const int warmup = int(p.integer("--warmup", 1, 0, 100000));
  const long batch = p.integer("--batch", 1, 1, 4096);
  const bool json = p.flag("--json");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  gpu::Context ctx(o);
  nn::ConvStack stack(ctx, widths, H, W, "bench", uint32_t(batch));
  stack.init_he(1);
  std::vector<float> v(stack.input().count());
  for (size_t i = 0; i < v.size(); ++i) v[i] = float((i * 2654435761u) % 1000) / 1000.0f;
  stack.input().upload(v);
  stack.output_grad().upload(std::vector<float>(stack.output().count(), 1e-3f));
  const Timing t = run_repeats(ctx, stack, warmup, repeats);
  std::vector<uint64_t> macs;
  for (size_t i = 0; i < stack.layers(); ++i) macs.push_back(stack.layer(i).macs({widths[i], H, W, uint32_t(batch)}));
  std::string list;
  for (uint32_t w : widths) {
    if (!list.empty()) list += ',';
    list += std::to_string(w);
  }
  char head[512];
  if (json) {
    std::snprintf(head, sizeof head,
                  "{\"bench\": \"conv\", \"device\": \"%s\", \"width\": %u, \"height\": %u, \"batch\": %ld, "
                  "\"widths\": [%s], \"repeats\": %d",
                  ctx.caps().name.c_str(), W, H, batch, list.c_str(), repeats);
    print_json(macs, t, head);
  } else {
    std::snprintf(head, sizeof head, "conv bench on %s: %ld x %ux%u, 3x3 widths %s, median of %d",
                  ctx.caps().name.c_str(), batch, W, H, list.c_str(), repeats);
    print_table(macs, t, head);
  }
  return 0;
}

}  // namespace evflow::app
