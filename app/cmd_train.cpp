// evflow train DATA --out RUN [--config FILE] [--preset fast|paper] [key=value ...]
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "io/atomic_file.h"
#include "train/checkpoint.h"
#include "train/trainer.h"

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

static int run_train(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf("usage: evflow train DATA --out RUN [--config FILE.json] [--preset fast|paper] [--resume] [--device N|name] [key=value ...]\n"
                "  DATA: a dataset folder (our layout, E3NeRF Real-World-Challenge or EBAD-NeRF; docs/datasets.md).\n"
                "  RUN: output folder: config.json, train.log, curve.csv, checkpoint.ckpt.\n  keys:");
    for (auto& k : TrainConfig::keys()) std::printf(" %s", k.c_str());
    std::printf("\n  (docs/training.md gives each key's meaning and default)\n");
    return 0;
  }
  const std::string out = p.value("--out");
  const std::string config_file = p.value("--config");
  const std::string preset = p.value("--preset");
  const bool resume = p.flag("--resume");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  std::vector<std::string> pos = p.positional(), overrides;
  std::string data_dir;
  for (auto& s : pos) (s.find('=') != std::string::npos ? overrides.push_back(s) : (void)(data_dir = s));
  if (data_dir.empty() || out.empty()) throw std::invalid_argument("usage: evflow train DATA --out RUN (see --help)");

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
  fs::create_directories(out);
  nlohmann::json saved = cfg.to_json();
  saved["data"] = fs::absolute(data_dir).string();
  write_text(fs::path(out) / "config.json", saved.dump(2) + "\n");
  gpu::Context ctx(o);

  const fs::path ckpt_path = fs::path(out) / "checkpoint.ckpt";
  std::unique_ptr<Trainer> trainer;
  if (resume) {
    trainer = std::make_unique<Trainer>(ctx, data, cfg, read_checkpoint(ckpt_path));
  } else {
    trainer = std::make_unique<Trainer>(ctx, data, cfg);
  }
  std::ofstream log(fs::path(out) / "train.log", resume ? std::ios::app : std::ios::trunc);
  std::ofstream curve(fs::path(out) / "curve.csv", resume ? std::ios::app : std::ios::trunc);
  if (!resume) curve << "step,view,loss,ms\n";
  const bool tty = isatty(fileno(stdout));
  std::printf("training %zu views (%s) on %s, %u Gaussians, %u iterations, preset %s\n", data.train.size(), data.layout.c_str(),
              ctx.caps().name.c_str(), cfg.init_gaussians, cfg.iterations, cfg.preset.c_str());
  std::signal(SIGINT, on_sigint);
  auto save = [&] { write_checkpoint(ckpt_path, trainer->checkpoint()); };
  double ema_ms = 0, ema_loss = 0;
  while (trainer->current_step() < cfg.iterations && !g_interrupted) {
    StepStats st = trainer->step();
    ema_ms = ema_ms ? 0.95 * ema_ms + 0.05 * st.ms : st.ms;
    if (!st.skipped) ema_loss = ema_loss ? 0.95 * ema_loss + 0.05 * st.loss : st.loss;
    curve << st.step << "," << st.view << "," << st.loss << "," << st.ms << "\n";
    if (st.skipped) log << "step " << st.step << ": non-finite loss on view " << st.view << ", skipped\n";
    const double eta = (cfg.iterations - st.step) * ema_ms / 1000.0;
    if (tty) {
      std::printf("\r[%5.1f%%] step %u/%u  %.1f it/s  ETA %.0fs  loss %.4f  Gaussians %zu ", 100.0 * st.step / cfg.iterations, st.step,
                  cfg.iterations, 1000.0 / ema_ms, eta, ema_loss, trainer->params().count);
      std::fflush(stdout);
    }
    if (st.step % cfg.log_every == 0 || st.step == cfg.iterations) {
      char line[256];
      std::snprintf(line, sizeof line, "step %u/%u  %.2f it/s  ETA %.0fs  loss %.5f  Gaussians %zu", st.step, cfg.iterations,
                    1000.0 / ema_ms, eta, ema_loss, trainer->params().count);
      log << line << "\n";
      log.flush();
      if (!tty) std::printf("%s\n", line);
    }
    if (cfg.checkpoint_every && st.step % cfg.checkpoint_every == 0) save();
  }
  save();
  if (tty) std::printf("\n");
  if (g_interrupted) std::printf("interrupted at step %u: checkpoint saved; continue with --resume\n", trainer->current_step());
  else std::printf("done: %u steps, checkpoint %s\n", trainer->current_step(), ckpt_path.c_str());
  return g_interrupted ? 130 : 0;
}

static Command reg("train", "train Gaussians on a dataset (checkpoints, log, loss curve)", run_train);

}  // namespace evflow::app
