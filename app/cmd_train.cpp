// evflow train DATA --out RUN [--config FILE] [--preset fast|paper] [--view ...] [key=value ...]
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "io/atomic_file.h"
#include "train/checkpoint.h"
#include "train/trainer.h"
#include "viewer/train_view.h"

namespace evflow::app {

namespace fs = std::filesystem;
static volatile std::sig_atomic_t g_interrupted = 0;
static void on_sigint(int) { g_interrupted = 1; }

static void write_text(const fs::path& p, const std::string& s) {
  io::write_file_atomic(p, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << s;
    if (!f) throw std::runtime_error(tmp.string() + ": write failed");
  });
}

// The keys with their defaults, one line per settings group, wrapped.
static void print_keys_brief() {
  std::string group, line;
  auto flush = [&] { if (!line.empty()) std::printf("%s\n", line.c_str()); line.clear(); };
  for (const SettingDoc& r : TrainConfig::describe()) {
    if (r.group != group) {
      flush();
      std::printf("    %s:\n", r.group.c_str());
      group = r.group;
    }
    const std::string item = " " + r.key + "=" + r.value;
    if (line.size() + item.size() > 100) flush();
    line += (line.empty() ? "     " : "") + item;
  }
  flush();
}

static int run_train(const Args& a) {
  ArgParser p(a);
  if (p.flag("--keys")) {
    std::printf("%s", TrainConfig::describe_markdown().c_str());
    return 0;
  }
  if (p.flag("--help")) {
    std::printf("usage: evflow train DATA --out RUN [--config FILE.json] [--preset fast|paper] [--resume] [--device N|name] [key=value ...]\n"
                "  DATA: a dataset folder (our layout, E3NeRF Real-World-Challenge or EBAD-NeRF; docs/datasets.md).\n"
                "  RUN: output folder: config.json, train.log, curve.csv, checkpoint.ckpt.\n"
                "  keys with their defaults (--keys: the tables of docs/training.md, each key's meaning):\n");
    print_keys_brief();
    std::printf(
                "  --view: watch training live in a window (docs/viewer.md): the splats from a free camera, and for\n"
                "    one training view its blurry input, the mid-exposure render, the virtual frames along the\n"
                "    exposure and the events; overlay with step, loss, PSNR, Gaussians, it/s.\n"
                "    keys: Space pause/resume, N single step (pauses first), Right/] and Left/[ next/previous view,\n"
                "    1-4 toggle panels, O overlay, R reset camera, Esc close the viewer (training goes on);\n"
                "    mouse: left-drag orbit, wheel zoom; W/A/S/D/Q/E fly.\n"
                "    --view-width 1280 --view-height 720   window size\n"
                "    --view-budget 0.1     viewer share of the wall time while training runs\n"
                "    --view-fps-cap 30     frame cap (0: none)   --view-refresh 1   panel re-render interval, s\n"
                "    --view-index V        training view shown first   --view-paused   start paused\n"
                "    --view-hold           keep the window open after training until it is closed\n"
                "    --view-frames N       close the viewer after N frames (training goes on)\n"
                "    --view-screenshot F.png, --view-report F.json   written when the viewer closes\n"
                "    --view-script \"FRAME:KEY,...\"   (testing) press KEY (space, n, right, left, 1-4, o, r) before FRAME\n");
    return 0;
  }
  const std::string out = p.value("--out");
  const std::string config_file = p.value("--config");
  const std::string preset = p.value("--preset");
  const bool resume = p.flag("--resume");
  const bool view = p.flag("--view");
  viewer::TrainViewOptions vo;
  vo.width = static_cast<uint32_t>(p.integer("--view-width", vo.width));
  vo.height = static_cast<uint32_t>(p.integer("--view-height", vo.height));
  vo.budget = p.number("--view-budget", vo.budget);
  vo.fps_cap = p.number("--view-fps-cap", vo.fps_cap);
  vo.refresh_s = p.number("--view-refresh", vo.refresh_s);
  vo.view = static_cast<int>(p.integer("--view-index", 0));
  vo.start_paused = p.flag("--view-paused");
  vo.hold = p.flag("--view-hold");
  vo.frames = static_cast<int>(p.integer("--view-frames", 0));
  vo.screenshot = p.value("--view-screenshot");
  vo.report = p.value("--view-report");
  vo.script = p.value("--view-script");
  vo.vsync = p.flag("--view-vsync");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  std::vector<std::string> pos = p.positional(), overrides;
  std::string data_dir;
  for (auto& s : pos) (s.find('=') != std::string::npos ? overrides.push_back(s) : (void)(data_dir = s));
  if (data_dir.empty() || out.empty()) throw std::invalid_argument("usage: evflow train DATA --out RUN (see --help)");
  if (!view) {
    for (const char* opt : {"--view-width", "--view-height", "--view-budget", "--view-fps-cap", "--view-refresh", "--view-index",
                            "--view-paused", "--view-hold", "--view-frames", "--view-screenshot", "--view-report",
                            "--view-script", "--view-vsync"})
      for (const auto& arg : a)
        if (arg == opt || arg.rfind(std::string(opt) + "=", 0) == 0)
          throw std::invalid_argument(std::string(opt) + " needs --view");
  } else {
    if (vo.width < 64 || vo.height < 64 || vo.width > 16384 || vo.height > 16384)
      throw std::invalid_argument("--view-width/--view-height must be in 64..16384");
    if (!(vo.budget > 0 && vo.budget <= 1)) throw std::invalid_argument("--view-budget must be in (0, 1]");
    if (!(vo.refresh_s >= 0)) throw std::invalid_argument("--view-refresh must be >= 0 seconds");
    if (vo.frames < 0) throw std::invalid_argument("--view-frames must be >= 0");
  }

  TrainConfig cfg;
  if (!config_file.empty()) {
    std::ifstream f(config_file);
    if (!f) throw std::runtime_error(config_file + ": cannot open config");
    nlohmann::json j;
    try { f >> j; } catch (const std::exception& e) { throw std::runtime_error(config_file + ": " + e.what()); }
    cfg.apply_json(j);
  }
  if (!preset.empty()) cfg.set("preset", preset);
  for (auto& kv : overrides) cfg.set(kv.substr(0, kv.find('=')), kv.substr(kv.find('=') + 1));

  io::Dataset data = io::load_dataset(data_dir);
  if (view) {
    if (vo.view < 0 || size_t(vo.view) >= data.train.size())
      throw std::invalid_argument("--view-index " + std::to_string(vo.view) + ": the dataset has " +
                                  std::to_string(data.train.size()) + " training views (0.." +
                                  std::to_string(data.train.size() - 1) + ")");
    viewer::TrainView::parse_script(vo.script);  // throws on a bad script before a window opens
  }
  fs::create_directories(out);
  nlohmann::json saved = cfg.to_json();
  saved["data"] = fs::absolute(data_dir).string();
  write_text(fs::path(out) / "config.json", saved.dump(2) + "\n");
  // With --view the context comes from the window (presentation on) and outlives the trainer.
  std::unique_ptr<viewer::Display> display;
  std::unique_ptr<gpu::Context> own_ctx;
  if (view) display = std::make_unique<viewer::Display>("evflow train --view", vo.width, vo.height, "evflow train", o, vo.vsync);
  else own_ctx = std::make_unique<gpu::Context>(o);
  gpu::Context& ctx = display ? display->context() : *own_ctx;

  const fs::path ckpt_path = fs::path(out) / "checkpoint.ckpt";
  std::unique_ptr<Trainer> trainer;
  if (resume) {
    trainer = std::make_unique<Trainer>(ctx, data, cfg, read_checkpoint(ckpt_path));
  } else {
    trainer = std::make_unique<Trainer>(ctx, data, cfg);
  }
  std::ofstream log(fs::path(out) / "train.log", resume ? std::ios::app : std::ios::trunc);
  std::ofstream curve(fs::path(out) / "curve.csv", resume ? std::ios::app : std::ios::trunc);
  if (!resume) {  // the weighted total, then every registered term's unweighted value
    curve << "step,view,loss,ms,flipped";
    for (auto& t : trainer->losses()) curve << "," << t->name();
    curve << "\n";
  }
  const bool tty = isatty(fileno(stdout));
  std::printf("training %zu views (%s) on %s, %u Gaussians, %u iterations, preset %s\n", data.train.size(), data.layout.c_str(),
              ctx.caps().name.c_str(), cfg.init_gaussians, cfg.iterations, cfg.preset.c_str());
  std::signal(SIGINT, on_sigint);
  std::unique_ptr<viewer::TrainView> tv;
  if (display) tv = std::make_unique<viewer::TrainView>(*display, *trainer, data, vo, &g_interrupted);
  auto save = [&] { write_checkpoint(ckpt_path, trainer->checkpoint()); };
  double ema_ms = 0, ema_loss = 0;
  const auto t_start = std::chrono::steady_clock::now();
  const uint32_t first_step = trainer->current_step();
  while (trainer->current_step() < cfg.iterations && !g_interrupted) {
    if (tv) {
      tv->before_step();
      if (g_interrupted) break;
    }
    StepStats st = trainer->step();
    if (tv) tv->after_step(st);
    ema_ms = ema_ms ? 0.95 * ema_ms + 0.05 * st.ms : st.ms;
    if (!st.skipped) ema_loss = ema_loss ? 0.95 * ema_loss + 0.05 * st.loss : st.loss;
    curve << st.step << "," << st.view << "," << st.loss << "," << st.ms << "," << (st.flipped ? 1 : 0);
    for (double v : st.term_values) curve << "," << v;
    curve << "\n";
    if (st.skipped) log << "step " << st.step << ": non-finite loss on view " << st.view << ", skipped\n";
    if (st.flipped)
      log << "step " << st.step << ": view " << st.view << " (" << data.train[st.view].name
          << "): trajectory reversed in time (the events scored the reversed order lower)\n";
    const double eta = (cfg.iterations - st.step) * ema_ms / 1000.0;
    if (tty) {
      std::printf("\r[%5.1f%%] step %u/%u  %.1f it/s  ETA %.0fs  loss %.4f  Gaussians %zu ", 100.0 * st.step / cfg.iterations, st.step,
                  cfg.iterations, 1000.0 / ema_ms, eta, ema_loss, trainer->params().count);
      std::fflush(stdout);
    }
    if (st.step % cfg.log_every == 0 || st.step == cfg.iterations) {
      char line[256];
      std::snprintf(line, sizeof line, "step %u/%u  %.2f it/s  ETA %.0fs  loss %.5f  Gaussians %zu  flips %u", st.step,
                    cfg.iterations, 1000.0 / ema_ms, eta, ema_loss, trainer->params().count, trainer->trajectory_flips());
      log << line << "\n";
      log.flush();
      if (!tty) std::printf("%s\n", line);
    }
    if (cfg.checkpoint_every && st.step % cfg.checkpoint_every == 0) save();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  save();
  if (tty) std::printf("\n");
  const uint32_t done_steps = trainer->current_step() - first_step;
  if (done_steps > 0)
    std::printf("training wall time %.2f s for %u steps: %.3f it/s%s\n", wall, done_steps, done_steps / wall,
                tv ? " (viewer on)" : "");
  if (g_interrupted) std::printf("interrupted at step %u: checkpoint saved; continue with --resume\n", trainer->current_step());
  else std::printf("done: %u steps, checkpoint %s\n", trainer->current_step(), ckpt_path.c_str());
  int status = g_interrupted ? 130 : 0;
  if (tv) {
    if (!g_interrupted) tv->after_training();
    tv->close();
    tv.reset();
    trainer.reset();
    const int v = viewer::report_validation(ctx, "evflow train --view");
    if (v && !status) status = v;
  }
  return status;
}

static Command reg("train", "train Gaussians on a dataset (checkpoints, log, loss curve)", run_train);

}  // namespace evflow::app
