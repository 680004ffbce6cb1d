// `evflow train --view`: the viewer open while training runs in the same process, on the same
// gpu::Context and the trainer's parameter buffers (docs/viewer.md). Single-threaded: the
// training loop calls before_step() / after_step() around each Trainer::step(); a viewer frame
// is drawn only while the viewer's share of the wall time stays within a budget, and window
// events are polled every step.
#pragma once
#include <csignal>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/dataset.h"
#include "train/trainer.h"
#include "viewer/canvas.h"
#include "viewer/layout.h"
#include "viewer/ui_layer.h"
#include "viewer/window.h"

namespace evflow::viewer {

struct TrainViewOptions {
  uint32_t width = 1280, height = 720;  // window size (screen coordinates)
  int frames = 0;                       // > 0: the viewer closes after this many presented frames
  std::string screenshot;               // PNG of the last presented frame (written when the viewer closes)
  std::string report;                   // JSON: per-frame step/paused/view, panel rectangles, PSNR, time share
  double budget = 0.10;                 // viewer time / wall time while training runs
  double fps_cap = 30.0;                // <= 0: uncapped
  double refresh_s = 1.0;               // the training-view panels re-render at most this often while training runs
  bool start_paused = false;
  bool hold = false;   // keep the window open after training ends, until it is closed
  int view = 0;        // training view shown first
  std::string script;  // testing: "FRAME:ACTION,..." (a key or a widget action) just before frame FRAME is drawn
  bool vsync = false;
  std::string shot_dir = ".";  // where the UI's screenshot button writes
};

// One item of --view-script: a key press, a click on a named widget, or a press at a fraction of
// a named slider's width (which sets the slider there).
struct ScriptAction {
  int key = 0;         // GLFW key, or 0 for a widget action
  std::string widget;  // "pause", "u", "weight.l1", ... (docs/viewer.md)
  double at = -1;      // < 0: click the widget's centre; else the fraction of its width to press at
};

// Everything the side panels show for the chosen training view, refreshed together.
struct ShownView {
  uint32_t view = 0;
  bool inputs_ready = false;       // blurry + events (depend on the view only)
  uint32_t step = UINT32_MAX;      // training step of the renders below
  uint32_t width = 0, height = 0;  // the view's image size
  gpu::Buffer blurry;              // planar linear RGB, width x height
  uint32_t events_w = 0, events_h = 0;
  gpu::Buffer events;  // planar linear RGB, events_w x events_h
  size_t events_pos = 0, events_neg = 0;
  bool has_events = false;
  double u = 0.5;                   // the exposure time `mid` was rendered at (blur mode)
  gpu::Buffer mid;                  // render at u along the exposure (plain mode: the view's camera)
  std::vector<double> times;        // blur mode: the virtual frames' exposure times u
  std::vector<gpu::Buffer> frames;  // blur mode: renders at those times
  // Flow panels (a run that uses flow): interval `interval` of `intervals`, from the trainer.
  bool has_flow = false, has_warped = false;
  uint32_t interval = 0, intervals = 0;
  double flow_max_px = 0;                 // the colour wheel's full saturation
  gpu::Buffer flow, measured, predicted;  // colour wheel, M_i, P_i: planar sRGB, width x height
  // LDI panel (ldi=on, loaded only while the panel is shown): the LDI network's frames at
  // `times` over the whole view, planar sRGB.
  bool has_ldi = false;
  std::vector<gpu::Buffer> ldi_frames;
  // Residual panel (res_weight > 0, loaded only while the panel is shown): per non-middle frame i
  // (residual_frames), the prior's R(t_i) and the renders' F_i - F_N as signed images
  // (residual_image.h), in pairs, on one scale.
  bool has_residuals = false;
  std::vector<uint32_t> residual_frames;
  std::vector<gpu::Buffer> residuals;  // planar sRGB: prior_i, render_i, ...
  double residual_scale = 0;
  double psnr = 0;             // model image (blur: mean of the frames) vs the training target
  double psnr_mid_sharp = -1;  // mid render vs the sharp ground truth (when the view has one)
};

struct Tile {
  const gpu::Buffer* rgb = nullptr;
  uint32_t width = 0, height = 0;
};

// A side panel: a label and a few images (tiles) of the shown training view. Panels are a
// list; a new one derives from Panel, takes its data from ShownView or its own refresh(), and
// is appended in TrainView's constructor with its toggle key.
class Panel {
 public:
  Panel(std::string id, int key) : id_(std::move(id)), key_(key) {}
  virtual ~Panel() = default;
  const std::string& id() const { return id_; }
  int key() const { return key_; }  // GLFW key that toggles it
  bool visible = true;
  virtual bool available(const ShownView&) const { return true; }
  virtual std::string label(const ShownView&) const = 0;
  virtual std::vector<Tile> tiles(const ShownView&) const = 0;
  // Tiles come in groups of this many that keep to one row of the panel's grid.
  virtual uint32_t group() const { return 1; }
  // Called after ShownView was refreshed (for panels with their own content).
  virtual void refresh(const ShownView&) {}

 private:
  std::string id_;
  int key_;
};

class TrainView {
 public:
  // `display` must outlive the trainer's GPU work (its context is the trainer's).
  TrainView(Display& display, Trainer& trainer, const io::Dataset& data, const TrainViewOptions& options,
            const volatile std::sig_atomic_t* interrupted = nullptr);
  ~TrainView();

  // Before each training step: polls window events and, while paused with no single step
  // requested, keeps drawing (at the frame cap) until resumed, stepped, closed or interrupted.
  void before_step();
  // After each step: records its statistics and draws a frame when the time budget allows.
  void after_step(const StepStats& st);
  // After the last step: keeps drawing while --frames are missing or --view-hold asks for it.
  void after_training();
  // Closes the viewer (writes the screenshot and report) if still open.
  void close();
  bool open() const { return open_; }

  // The key handler (window keys and the test script). Keys are documented in docs/viewer.md.
  void press(int key);
  static int key_from_name(const std::string& name);  // "space", "n", "right", "1", ...; throws on unknown names
  // "FRAME:KEY,FRAME:click=WIDGET,FRAME:slide=WIDGET@FRACTION,..." -> frame -> actions; throws
  // std::invalid_argument naming the bad item.
  static std::map<int, std::vector<ScriptAction>> parse_script(const std::string& script);

 private:
  void draw_frame();
  std::vector<std::pair<Rect, std::string>> compose();
  bool present_frame(const std::vector<std::pair<Rect, std::string>>& labels);
  // The side panels' content; `renders` false: only the view's inputs (blurry, events).
  void refresh_content(bool renders);
  void load_view_inputs();
  void load_snapshot(uint32_t step);
  void load_flow(const ViewSnapshot& snap);
  void load_ldi(const ViewSnapshot& snap);
  void load_residuals(const ViewSnapshot& snap);
  bool panel_visible(const std::string& id) const;
  void render_free_view(const Rect& m);
  void poll();
  void apply_script(int frame);
  void run_widget_action(const ScriptAction& a);
  // The ImGui windows and the panels' labels (train_ui.cpp); `labels`: each shown panel's label
  // strip and text.
  void build_ui(const std::vector<std::pair<Rect, std::string>>& labels);
  void build_stats();
  void build_controls();
  void build_weights();
  void request_view(uint32_t v);
  Orbit view_orbit(uint32_t v) const;
  void save_frame(const std::string& path);
  nlohmann::json report() const;

  Display& display_;
  Trainer& trainer_;
  const io::Dataset& data_;
  TrainViewOptions opt_;
  const volatile std::sig_atomic_t* interrupted_;
  gpu::Context& ctx_;
  gpu::Commands cmd_;
  Rasterizer raster_;
  RenderState free_view_;  // the free camera's render
  Canvas canvas_;
  std::unique_ptr<UiLayer> ui_;
  gpu::Buffer readback_;  // the presented frame with the UI, for screenshots
  ShownView shown_;
  std::vector<std::unique_ptr<Panel>> panels_;
  std::map<int, std::vector<ScriptAction>> script_;  // frame -> actions
  std::vector<ScriptAction> pending_widgets_;        // widget actions for the next frame
  double u_ = 0.5;                                   // the u slider: exposure time the render panel shows
  uint32_t interval_ = 0;                            // the interval slider: the flow panels' interval
  bool shot_requested_ = false;
  bool first_frame_light_ = false;  // the first frame while training runs: no panel renders
  int shots_ = 0;
  std::string last_shot_;
  // What the free camera last rendered: the splats' step, the orbit and the size.
  uint32_t free_step_ = UINT32_MAX;
  Orbit free_orbit_;
  uint32_t free_w_ = 0, free_h_ = 0;
  double last_free_ = -1e9;
  // Loss history for the plots: the total and each term's unweighted value, one entry per step.
  std::vector<float> loss_hist_;
  std::vector<std::vector<float>> term_hist_;
  std::vector<float> weight_max_;  // each loss weight slider's upper end (fixed when the UI opens)
  bool plots_ = true;              // the loss plots shown in the UI
  Orbit home_;                     // where the free camera started or was last sent (R)
  Orbit centre_;                   // the initial cloud's centre and size
  std::array<double, 9> frame_;    // the orbit's frame: up as the training cameras hold it
  bool open_ = true, paused_ = false, training_done_ = false;
  bool overlay_ = true;  // the UI window shown (O)
  int step_requests_ = 0;
  uint32_t view_ = 0;
  // Time budget (seconds): credit grows by budget x wall time while training runs, a frame costs
  // its duration; a frame is drawn when the credit is >= 0.
  // viewer_s_ counts frames drawn while training runs; other_s_ the frames while paused or after
  // training (not charged).
  double credit_ = 0, viewer_s_ = 0, other_s_ = 0, training_wall_s_ = 0;
  double frame_cost_ = 0;  // running average of a charged frame's duration
  double last_mark_ = 0, next_frame_ = 0, last_poll_ = 0, last_refresh_ = -1e9;
  double start_ = 0;
  // Statistics for the UI.
  uint32_t last_step_ = 0;
  double loss_ema_ = -1, last_loss_ = 0, its_ema_ = 0, last_step_time_ = -1;
  int frames_shown_ = 0;
  Rect main_rect_;
  std::vector<std::pair<std::string, std::vector<std::pair<Rect, Tile>>>> last_tiles_;
  std::vector<nlohmann::json> frame_log_;
};

}  // namespace evflow::viewer
