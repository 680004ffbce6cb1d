// evflow train DATA --out RUN [--config FILE] [--preset fast|paper] [--view ...] [key=value ...]
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <type_traits>

#include "cli.h"
#include "io/atomic_file.h"
#include "nn/safetensors.h"
#include "resume_files.h"
#include "train/checkpoint.h"
#include "train/trainer.h"
#include "train_curve.h"
#include "viewer/train_view.h"

namespace evflow::app {

namespace fs = std::filesystem;
static volatile std::sig_atomic_t g_interrupted = 0;
static void on_sigint(int) { g_interrupted = 1; }

static void write_text(const fs::path& p, const std::string& s) {
  io::write_file_atomic(p, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << s;
    io::close_or_throw(f, p);
  });
}

// The --view-* options: each one's name, argument, member, help and allowed values, once.
using viewer::TrainViewOptions;
struct ViewOption {
  const char* name;
  const char* arg;  // "" for a flag
  std::function<void(ArgParser&, TrainViewOptions&)> read;
  std::function<std::string(const TrainViewOptions&)> shown;  // the value as help shows it
  const char* doc;
  const char* allowed = "";  // "in 64..16384": the error reads "NAME must be in 64..16384"
  std::function<bool(const TrainViewOptions&)> valid = nullptr;
};

// An option stored in one member of TrainViewOptions, read as the member's type.
template <typename T>
static ViewOption view_option(const char* name, const char* arg, T TrainViewOptions::*m, const char* doc,
                              const char* allowed = "", std::function<bool(const T&)> valid = nullptr) {
  ViewOption o{name, arg, nullptr, nullptr, doc, allowed, nullptr};
  if constexpr (std::is_same_v<T, bool>)
    o.read = [=](ArgParser& p, TrainViewOptions& v) { v.*m = p.flag(name); };
  else if constexpr (std::is_same_v<T, std::string>)
    o.read = [=](ArgParser& p, TrainViewOptions& v) { v.*m = p.value(name); };
  else if constexpr (std::is_integral_v<T>)
    o.read = [=](ArgParser& p, TrainViewOptions& v) { v.*m = T(p.integer(name, v.*m)); };
  else
    o.read = [=](ArgParser& p, TrainViewOptions& v) { v.*m = p.number(name, v.*m); };
  o.shown = [=](const TrainViewOptions& v) {
    if constexpr (std::is_same_v<T, bool>)
      return std::string(v.*m ? "on" : "off");
    else if constexpr (std::is_same_v<T, std::string>)
      return v.*m;
    else {
      char b[32];
      std::snprintf(b, sizeof b, "%g", double(v.*m));
      return std::string(b);
    }
  };
  if (valid) o.valid = [=](const TrainViewOptions& v) { return valid(v.*m); };
  return o;
}

static const std::vector<ViewOption>& view_options() {
  using O = TrainViewOptions;
  static const std::vector<ViewOption> table = {
      view_option<uint32_t>("--view-width", "W", &O::width, "window width", "in 64..16384",
                            [](const uint32_t& w) { return w >= 64 && w <= 16384; }),
      view_option<uint32_t>("--view-height", "H", &O::height, "window height", "in 64..16384",
                            [](const uint32_t& h) { return h >= 64 && h <= 16384; }),
      view_option<double>("--view-budget", "B", &O::budget, "the viewer's share of the wall time while training runs",
                          "in (0, 1]", [](const double& b) { return b > 0 && b <= 1; }),
      view_option<double>("--view-fps-cap", "F", &O::fps_cap, "at most F frames per second; 0: no cap"),
      view_option<double>("--view-refresh", "S", &O::refresh_s,
                          "while training runs, re-render the training-view panels and the free camera's splats at "
                          "most every S seconds",
                          ">= 0", [](const double& s) { return s >= 0; }),
      view_option<int>("--view-index", "V", &O::view,
                       "training view shown first, 0-based, checked against the dataset"),
      view_option<bool>("--view-paused", "", &O::start_paused, "start paused (look first, then Space)"),
      view_option<bool>("--view-hold", "", &O::hold,
                        "after the last step keep the window open (state \"done\") until it is closed"),
      view_option<bool>("--view-vsync", "", &O::vsync, "present with vsync (FIFO)"),
      view_option<int>("--view-frames", "N", &O::frames,
                       "close the viewer after N presented frames (training goes on); 0: never", ">= 0",
                       [](const int& n) { return n >= 0; }),
      view_option<std::string>("--view-screenshot", "F.png", &O::screenshot,
                               "the last presented frame with the UI, written when the viewer closes"),
      view_option<std::string>(
          "--view-report", "F.json", &O::report,
          "written when the viewer closes: per frame {frame, step, paused, view, content_step, u, panels, ms}, "
          "the panels' tile rectangles (with source sizes), the free-camera rectangle, the UI widgets' "
          "rectangles, the shown view's PSNR, event counts, flow, LDI frames and residuals, u, the loss weights, "
          "screenshots taken, viewer and training wall seconds"),
      view_option<std::string>(
          "--view-script", "\"F:ACTION,...\"", &O::script,
          "testing: just before frame F is drawn, presses a key (space, n, right, left, 1-9, o, r), clicks a UI "
          "widget (click=pause) or presses a slider at a fraction of its range (slide=u@0.25); widget names in "
          "docs/viewer.md"),
  };
  return table;
}

// "(default 1280; in 64..16384)" for help and docs; empty for an option with neither.
static std::string view_option_limits(const ViewOption& v) {
  const std::string def = *v.arg ? v.shown(TrainViewOptions{}) : "";
  std::string s = def.empty() ? "" : "default " + def;
  if (*v.allowed) s += (s.empty() ? "" : "; ") + std::string(v.allowed);
  return s.empty() ? "" : " (" + s + ")";
}

static TrainViewOptions read_view_options(ArgParser& p) {
  TrainViewOptions vo;
  for (const ViewOption& v : view_options()) v.read(p, vo);
  return vo;
}

// Without --view every --view-* option is an error; with it, each value must be allowed.
static void check_view_options(const TrainViewOptions& vo, const Args& a, bool view) {
  for (const ViewOption& v : view_options()) {
    const std::string name = v.name;
    if (!view) {
      for (const auto& arg : a)
        if (arg == name || arg.rfind(name + "=", 0) == 0) throw std::invalid_argument(name + " needs --view");
    } else if (v.valid && !v.valid(vo)) {
      throw std::invalid_argument(name + " must be " + v.allowed);
    }
  }
}

// The options as the markdown table of docs/viewer.md.
static std::string view_options_markdown() {
  std::string md = "| option | meaning |\n|---|---|\n";
  for (const ViewOption& v : view_options())
    md += "| `" + std::string(v.name) + (*v.arg ? " " : "") + v.arg + "` | " + v.doc + view_option_limits(v) + " |\n";
  return md;
}

// The keys with their defaults, one line per settings group, wrapped.
static void print_keys_brief() {
  std::string group, line;
  auto flush = [&] {
    if (!line.empty()) std::printf("%s\n", line.c_str());
    line.clear();
  };
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

static void print_help() {
  std::printf(
      "usage: evflow train DATA --out RUN [--config FILE.json] [--preset fast|paper] [--resume] [--device N|name] "
      "[key=value ...]\n"
      "  DATA: a dataset folder (our layout, E3NeRF Real-World-Challenge or EBAD-NeRF; docs/datasets.md).\n"
      "  RUN: output folder: config.json, train.log, curve.csv, curve.png, checkpoint.ckpt (and ldi.safetensors\n"
      "    with ldi=on).\n"
      "  keys with their defaults (--keys: the tables of docs/training.md, each key's meaning):\n");
  print_keys_brief();
  std::printf(
      "  --view: watch training live in a window (docs/viewer.md): the splats from a free camera, and for\n"
      "    one training view its blurry input, a render at u along the exposure, the virtual frames along the\n"
      "    exposure and the events, in runs that use flow one interval's flow and warped events, with ldi=on\n"
      "    the LDI network's frames, with res_weight > 0 the prior's residuals beside the renders';\n"
      "    a UI window (Dear ImGui) with step, loss plots, PSNR, Gaussians, it/s, pause / step / view / u /\n"
      "    interval / panel / screenshot controls and the loss weights, live.\n"
      "    keys: Space pause/resume, N single step (pauses first), Right/] and Left/[ next/previous view,\n"
      "    1-8 toggle panels, O the UI window, R camera to the shown view, Esc close the viewer (training\n"
      "    goes on);\n"
      "    mouse: left-drag orbit, wheel zoom; W/A/S/D/Q/E fly. Its options (--view-options: as a table):\n");
  for (const ViewOption& v : view_options())
    std::printf("    %-26s %s%s\n", (std::string(v.name) + (*v.arg ? " " : "") + v.arg).c_str(), v.doc,
                view_option_limits(v).c_str());
}

// The settings: defaults, then the config file, the preset, the key=value overrides.
static TrainConfig read_config(const std::string& config_file, const std::string& preset,
                               const std::vector<std::string>& overrides) {
  TrainConfig cfg;
  if (!config_file.empty()) {
    std::ifstream f(config_file);
    if (!f) throw std::runtime_error(config_file + ": cannot open config");
    nlohmann::json j;
    try {
      f >> j;
      cfg.apply_json(j);
    } catch (const std::exception& e) { throw std::runtime_error(config_file + ": " + e.what()); }
  }
  if (!preset.empty()) cfg.set("preset", preset);
  for (auto& kv : overrides) cfg.set(kv.substr(0, kv.find('=')), kv.substr(kv.find('=') + 1));
  return cfg;
}

// A dataset that can be trained on, and a --view-index and script that fit it.
static void check_trainable(const io::Dataset& data, const std::string& data_dir, const TrainViewOptions& vo,
                            bool view) {
  if (data.layout == "recording")
    throw std::invalid_argument(data_dir + ": a recording has no camera poses yet; run `evflow poses " + data_dir +
                                "` and train on its output");
  if (!view) return;
  if (vo.view < 0 || size_t(vo.view) >= data.train.size())
    throw std::invalid_argument("--view-index " + std::to_string(vo.view) + ": the dataset has " +
                                std::to_string(data.train.size()) + " training views (0.." +
                                std::to_string(data.train.size() - 1) + ")");
  viewer::TrainView::parse_script(vo.script);  // throws on a bad script before a window opens
}

// A new trainer, or one continued from the run's checkpoint (and the LDI's state with ldi=on).
static std::unique_ptr<Trainer> make_trainer(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg,
                                             const fs::path& out, bool resume) {
  // Left by a run that was killed while saving (the LDI's weights, the checkpoint, then the curve's figure).
  for (const char* name : {"ldi.safetensors", "checkpoint.ckpt", "curve.png"}) io::remove_stale_temporaries(out / name);
  if (!resume) return std::make_unique<Trainer>(ctx, data, cfg);
  Checkpoint start = read_checkpoint(out / "checkpoint.ckpt");
  if (cfg.ldi) {
    const fs::path ldi_path = out / "ldi.safetensors";
    if (!fs::exists(ldi_path))
      throw std::runtime_error(ldi_path.string() + ": missing; an ldi=on run keeps the LDI's state there");
    start.ldi = nn::load_safetensors(ldi_path);
    start.ldi_source = ldi_path.string();
  }
  auto trainer = std::make_unique<Trainer>(ctx, data, cfg, start);
  trim_curve(out / "curve.csv", trainer->current_step());
  return trainer;
}

// The progress line on a terminal, and every log_every steps the log's line (also printed
// when stdout is not a terminal).
class Progress {
 public:
  Progress(const TrainConfig& cfg, const io::Dataset& data, std::ofstream& log)
      : cfg_(cfg), data_(data), log_(log), tty_(isatty(fileno(stdout))) {}

  void step(const Trainer& trainer, const StepStats& st, double psnr, bool log_step) {
    ema_ms_ = ema_ms_ ? 0.95 * ema_ms_ + 0.05 * st.ms : st.ms;
    if (!st.skipped) ema_loss_ = ema_loss_ ? 0.95 * ema_loss_ + 0.05 * st.loss : st.loss;
    if (st.skipped) log_ << "step " << st.step << ": non-finite loss on view " << st.view << ", skipped\n";
    if (st.flipped)
      log_ << "step " << st.step << ": view " << st.view << " (" << data_.train[st.view].name
           << "): trajectory reversed in time (the events scored the reversed order lower)\n";
    const double eta = (cfg_.iterations - st.step) * ema_ms_ / 1000.0;
    if (tty_) {
      std::printf("\r[%5.1f%%] step %u/%u  %.1f it/s  ETA %.0fs  loss %.4f  Gaussians %zu ",
                  100.0 * st.step / cfg_.iterations, st.step, cfg_.iterations, 1000.0 / ema_ms_, eta, ema_loss_,
                  trainer.params().count);
      std::fflush(stdout);
    }
    if (!log_step) return;
    char line[256];
    std::snprintf(line, sizeof line,
                  "step %u/%u  %.2f it/s  ETA %.0fs  loss %.5f  PSNR %.2f dB  Gaussians %zu  flips %u", st.step,
                  cfg_.iterations, 1000.0 / ema_ms_, eta, ema_loss_, psnr, trainer.params().count,
                  trainer.trajectory_flips());
    log_ << line << "\n";
    log_.flush();
    if (!tty_) std::printf("%s\n", line);
  }
  void end() const {
    if (tty_) std::printf("\n");
  }

 private:
  const TrainConfig& cfg_;
  const io::Dataset& data_;
  std::ofstream& log_;
  const bool tty_;
  double ema_ms_ = 0, ema_loss_ = 0;
};

// Steps until the last iteration or an interrupt, saving every checkpoint_every steps and at the end.
static void train_loop(Trainer& trainer, const TrainConfig& cfg, TrainCurve& curve, Progress& progress,
                       viewer::TrainView* tv, const std::function<void()>& save) {
  const auto t_start = std::chrono::steady_clock::now();
  const uint32_t first_step = trainer.current_step();
  while (trainer.current_step() < cfg.iterations && !g_interrupted) {
    if (tv) {
      tv->before_step();
      if (g_interrupted) break;
    }
    StepStats st = trainer.step();
    if (tv) tv->after_step(st);
    const bool log_step = st.step % cfg.log_every == 0 || st.step == cfg.iterations;
    const double psnr = curve.add(trainer, st, log_step);
    progress.step(trainer, st, psnr, log_step);
    if (cfg.checkpoint_every && st.step % cfg.checkpoint_every == 0) save();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  save();
  progress.end();
  const uint32_t done_steps = trainer.current_step() - first_step;
  if (done_steps > 0)
    std::printf("training wall time %.2f s for %u steps: %.3f it/s%s\n", wall, done_steps, done_steps / wall,
                tv ? " (viewer on)" : "");
}

static int run_train(const Args& a) {
  ArgParser p(a);
  if (p.flag("--keys")) return std::printf("%s", TrainConfig::describe_markdown().c_str()), 0;
  if (p.flag("--view-options")) return std::printf("%s", view_options_markdown().c_str()), 0;
  if (p.flag("--help")) return print_help(), 0;
  const std::string out_arg = p.value("--out"), config_file = p.value("--config"), preset = p.value("--preset");
  const bool resume = p.flag("--resume"), view = p.flag("--view");
  viewer::TrainViewOptions vo = read_view_options(p);
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  std::vector<std::string> overrides;
  std::string data_dir;
  for (auto& s : p.positional()) (s.find('=') != std::string::npos ? overrides.push_back(s) : (void)(data_dir = s));
  if (data_dir.empty() || out_arg.empty())
    throw std::invalid_argument("usage: evflow train DATA --out RUN (see --help)");
  check_view_options(vo, a, view);
  const TrainConfig cfg = read_config(config_file, preset, overrides);
  io::Dataset data = io::load_dataset(data_dir);
  check_trainable(data, data_dir, vo, view);
  const fs::path out = out_arg;
  fs::create_directories(out);
  // With --view the context comes from the window (presentation on) and outlives the trainer.
  std::unique_ptr<viewer::Display> display;
  std::unique_ptr<gpu::Context> own_ctx;
  if (view)
    display =
        std::make_unique<viewer::Display>("evflow train --view", vo.width, vo.height, "evflow train", o, vo.vsync);
  else
    own_ctx = std::make_unique<gpu::Context>(o);
  gpu::Context& ctx = display ? display->context() : *own_ctx;
  std::unique_ptr<Trainer> trainer = make_trainer(ctx, data, cfg, out, resume);
  std::ofstream log(out / "train.log", resume ? std::ios::app : std::ios::trunc);
  TrainCurve curve(out_arg, *trainer, resume);
  // Only now: a resume refused above leaves the run's own config.
  nlohmann::json saved = cfg.to_json();
  saved["data"] = fs::absolute(data_dir).string();
  write_text(out / "config.json", saved.dump(2) + "\n");
  std::printf("training %zu views (%s) on %s, %u Gaussians, %u iterations, preset %s\n", data.train.size(),
              data.layout.c_str(), ctx.caps().name.c_str(), cfg.init_gaussians, cfg.iterations, cfg.preset.c_str());
  std::signal(SIGINT, on_sigint);
  std::unique_ptr<viewer::TrainView> tv;
  vo.shot_dir = out_arg;  // the UI's screenshot button writes into the run folder
  if (display) tv = std::make_unique<viewer::TrainView>(*display, *trainer, data, vo, &g_interrupted);
  // The curve and the log reach the disk before the checkpoint does: a run killed after a save
  // has every row up to the checkpoint's step (--resume drops the rows past it).
  const fs::path ckpt_path = out / "checkpoint.ckpt";
  auto save = [&] {
    curve.flush();
    log.flush();
    const Checkpoint ckpt = trainer->checkpoint();
    if (ckpt.ldi) nn::save_safetensors(out / "ldi.safetensors", *ckpt.ldi);
    write_checkpoint(ckpt_path, ckpt);
    curve.plot();
  };
  Progress progress(cfg, data, log);
  train_loop(*trainer, cfg, curve, progress, tv.get(), save);
  if (g_interrupted)
    std::printf("interrupted at step %u: checkpoint saved; continue with --resume\n", trainer->current_step());
  else
    std::printf("done: %u steps, checkpoint %s\n", trainer->current_step(), ckpt_path.c_str());
  int status = g_interrupted ? 130 : 0;
  if (!tv) return status;
  if (!g_interrupted) tv->after_training();
  tv->close();
  tv.reset();
  trainer.reset();
  const int v = viewer::report_validation(ctx, "evflow train --view");
  return v && !status ? v : status;
}

static Command reg("train", "train Gaussians on a dataset (checkpoints, log, loss curve)", run_train);

}  // namespace evflow::app
