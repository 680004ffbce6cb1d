#include "viewer/train_view.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <imgui.h>

#include "io/image.h"
#include "metrics/srgb_metrics.h"
#include "viewer/event_image.h"
#include "viewer/flow_image.h"
#include "viewer/residual_image.h"
#include "viewer/view_camera.h"

namespace evflow::viewer {

namespace {

// While training runs the free camera renders at most this many times the shown training
// view's pixel count (its frames then cost about what the side panels' renders cost).
constexpr double kFreeCameraPixels = 2.0;

double now_s() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

constexpr uint32_t kBackground = rgba(32, 32, 32);

// PSNR on 8-bit sRGB images, as `evflow eval` scores (metrics/srgb_metrics.h).
double psnr(const std::vector<float>& a, const std::vector<float>& b) { return metrics::psnr_srgb(a, b); }

std::vector<float> encoded(std::vector<float> linear) {
  for (float& x : linear) x = io::linear_to_srgb(x);
  return linear;
}

// One buffer per image (planar, what the canvas shows), grown or shrunk to the images' count.
void upload_all(gpu::Context& ctx, std::vector<gpu::Buffer>& bufs, const std::vector<std::vector<float>>& images,
                const char* name) {
  while (bufs.size() < images.size()) bufs.emplace_back(ctx, 16, name);
  bufs.resize(images.size());
  for (size_t i = 0; i < images.size(); ++i) {
    bufs[i].ensure(images[i].size() * 4);
    bufs[i].write(images[i]);
  }
}

// The side panels.
class BlurryPanel : public Panel {
 public:
  BlurryPanel() : Panel("blurry", GLFW_KEY_1) {}
  std::string label(const ShownView& s) const override { return "1 blurry input"; }
  std::vector<Tile> tiles(const ShownView& s) const override { return {{&s.blurry, s.width, s.height}}; }
};

class MidPanel : public Panel {
 public:
  explicit MidPanel(bool blur) : Panel("mid", GLFW_KEY_2), blur_(blur) {}
  bool available(const ShownView& s) const override { return s.step != UINT32_MAX; }
  std::string label(const ShownView& s) const override {
    char u[32];
    std::snprintf(u, sizeof u, " at u = %.3f", s.u);
    return std::string("2 render") + (blur_ ? u : "") + ", step " + std::to_string(s.step);
  }
  std::vector<Tile> tiles(const ShownView& s) const override { return {{&s.mid, s.width, s.height}}; }

 private:
  bool blur_;
};

class VirtualFramesPanel : public Panel {
 public:
  VirtualFramesPanel() : Panel("virtual", GLFW_KEY_3) {}
  bool available(const ShownView& s) const override { return !s.frames.empty(); }
  std::string label(const ShownView& s) const override {
    return "3 virtual frames x" + std::to_string(s.frames.size());
  }
  std::vector<Tile> tiles(const ShownView& s) const override {
    std::vector<Tile> t;
    for (auto& f : s.frames) t.push_back({&f, s.width, s.height});
    return t;
  }
};

class EventsPanel : public Panel {
 public:
  EventsPanel() : Panel("events", GLFW_KEY_4) {}
  std::string label(const ShownView& s) const override {
    if (!s.has_events) return "4 events: none in the dataset";
    return "4 events +" + std::to_string(s.events_pos) + " -" + std::to_string(s.events_neg);
  }
  std::vector<Tile> tiles(const ShownView& s) const override { return {{&s.events, s.events_w, s.events_h}}; }
};

// The flow of the chosen interval as training uses it (flow=events, gt or model).
class FlowPanel : public Panel {
 public:
  FlowPanel() : Panel("flow", GLFW_KEY_5) {}
  bool available(const ShownView& s) const override { return s.has_flow; }
  std::string label(const ShownView& s) const override {
    char t[96];  // short: the label strip is as wide as the panel
    std::snprintf(t, sizeof t, "5 flow i=%u (%.2f px = full)", s.interval, s.flow_max_px);
    return t;
  }
  std::vector<Tile> tiles(const ShownView& s) const override { return {{&s.flow, s.width, s.height}}; }
};

// What the warped-event loss compares for the interval: measured M_i beside predicted P_i.
class WarpedPanel : public Panel {
 public:
  WarpedPanel() : Panel("warped", GLFW_KEY_6) {}
  bool available(const ShownView& s) const override { return s.has_warped; }
  std::string label(const ShownView& s) const override {
    const std::string i = std::to_string(s.interval);
    return "6 warped M_" + i + " | render P_" + i;
  }
  std::vector<Tile> tiles(const ShownView& s) const override {
    return {{&s.measured, s.width, s.height}, {&s.predicted, s.width, s.height}};
  }
};

// The LDI network's frames over the whole view (ldi=on), tiled as the virtual frames.
class LdiPanel : public Panel {
 public:
  LdiPanel() : Panel("ldi", GLFW_KEY_7) {}
  bool available(const ShownView& s) const override { return s.has_ldi; }
  std::string label(const ShownView& s) const override {
    return "7 LDI frames x" + std::to_string(s.ldi_frames.size());
  }
  std::vector<Tile> tiles(const ShownView& s) const override {
    std::vector<Tile> t;
    for (auto& f : s.ldi_frames) t.push_back({&f, s.width, s.height});
    return t;
  }
};

// What L_res compares (res_weight > 0): per non-middle frame, the prior's R(t_i) beside the
// renders' F_i - F_N.
class ResidualPanel : public Panel {
 public:
  ResidualPanel() : Panel("residual", GLFW_KEY_8) {}
  bool available(const ShownView& s) const override { return s.has_residuals; }
  std::string label(const ShownView& s) const override {
    return "8 residuals prior | render x" + std::to_string(s.residual_frames.size());
  }
  std::vector<Tile> tiles(const ShownView& s) const override {
    std::vector<Tile> t;
    for (auto& r : s.residuals) t.push_back({&r, s.width, s.height});
    return t;
  }
  uint32_t group() const override { return 2; }
};

}  // namespace

int TrainView::key_from_name(const std::string& n) {
  if (n == "space") return GLFW_KEY_SPACE;
  if (n == "n") return GLFW_KEY_N;
  if (n == "right" || n == "]") return GLFW_KEY_RIGHT;
  if (n == "left" || n == "[") return GLFW_KEY_LEFT;
  if (n == "o") return GLFW_KEY_O;
  if (n == "r") return GLFW_KEY_R;
  if (n.size() == 1 && n[0] >= '1' && n[0] <= '9') return GLFW_KEY_1 + (n[0] - '1');
  throw std::invalid_argument("--view-script: unknown key '" + n + "' (space, n, right, left, o, r, 1..9)");
}

std::map<int, std::vector<ScriptAction>> TrainView::parse_script(const std::string& script) {
  std::map<int, std::vector<ScriptAction>> out;
  std::stringstream ss(script);
  for (std::string item; std::getline(ss, item, ',');) {
    if (item.empty()) continue;
    const size_t colon = item.find(':');
    int frame = 0;
    try {
      if (colon == std::string::npos) throw 1;
      size_t pos = 0;
      frame = std::stoi(item.substr(0, colon), &pos);
      if (pos != colon || frame < 1) throw 1;
    } catch (...) {
      throw std::invalid_argument("--view-script: '" + item + "' is not FRAME:KEY with FRAME >= 1 (e.g. 3:space,5:n)");
    }
    const std::string what = item.substr(colon + 1);
    ScriptAction a;
    if (what.rfind("click=", 0) == 0) {
      a.widget = what.substr(6);
    } else if (what.rfind("slide=", 0) == 0) {
      const size_t at = what.find('@');
      bool ok = at != std::string::npos && at > 6;
      if (ok) {
        a.widget = what.substr(6, at - 6);
        char* end = nullptr;
        const std::string f = what.substr(at + 1);
        a.at = std::strtod(f.c_str(), &end);
        ok = !f.empty() && *end == 0 && a.at >= 0 && a.at <= 1;
      }
      if (!ok)
        throw std::invalid_argument(
            "--view-script: '" + item +
            "' is not FRAME:slide=WIDGET@FRACTION with FRACTION in [0, 1] (e.g. 3:slide=u@0.25)");
    } else {
      a.key = key_from_name(what);
    }
    if (a.key == 0 && a.widget.empty()) throw std::invalid_argument("--view-script: '" + item + "' names no widget");
    out[frame].push_back(a);
  }
  return out;
}

TrainView::TrainView(Display& display, Trainer& trainer, const io::Dataset& data, const TrainViewOptions& options,
                     const volatile std::sig_atomic_t* interrupted)
    : display_(display),
      trainer_(trainer),
      data_(data),
      opt_(options),
      interrupted_(interrupted),
      ctx_(display.context()),
      cmd_(ctx_),
      raster_(ctx_),
      free_view_(ctx_),
      canvas_(ctx_, cmd_),
      ui_(std::make_unique<UiLayer>(display)),
      readback_(ctx_, 16, "view_readback") {
  if (data_.train.empty()) throw std::invalid_argument("train --view: the dataset has no training views");
  if (opt_.view < 0 || size_t(opt_.view) >= data_.train.size())
    throw std::invalid_argument("--view-index " + std::to_string(opt_.view) + ": the dataset has " +
                                std::to_string(data_.train.size()) + " training views (0.." +
                                std::to_string(data_.train.size() - 1) + ")");
  if (!(opt_.budget > 0 && opt_.budget <= 1)) throw std::invalid_argument("--view-budget must be in (0, 1]");
  view_ = uint32_t(opt_.view);
  shown_.blurry = gpu::Buffer(ctx_, 16, "view_blurry");
  shown_.events = gpu::Buffer(ctx_, 16, "view_events");
  shown_.mid = gpu::Buffer(ctx_, 16, "view_mid");
  shown_.flow = gpu::Buffer(ctx_, 16, "view_flow");
  shown_.measured = gpu::Buffer(ctx_, 16, "view_measured");
  shown_.predicted = gpu::Buffer(ctx_, 16, "view_predicted");
  paused_ = opt_.start_paused;
  script_ = parse_script(opt_.script);

  const bool blur = trainer_.config().mode == TrainMode::Blur;
  panels_.push_back(std::make_unique<BlurryPanel>());
  panels_.push_back(std::make_unique<MidPanel>(blur));
  panels_.push_back(std::make_unique<VirtualFramesPanel>());
  panels_.push_back(std::make_unique<EventsPanel>());
  panels_.push_back(std::make_unique<FlowPanel>());
  panels_.push_back(std::make_unique<WarpedPanel>());
  if (trainer_.ldi()) panels_.push_back(std::make_unique<LdiPanel>());
  if (trainer_.config().res_weight > 0) panels_.push_back(std::make_unique<ResidualPanel>());

  centre_ = initial_orbit(trainer_.cloud());
  std::vector<Camera> cams;
  for (const io::View& v : data_.train) cams.push_back(v.camera);
  frame_ = basis_from_cameras(cams);
  display_.input().orbit = home_ = view_orbit(view_);
  display_.input().on_key = [this](int key, int) { press(key); };

  start_ = last_mark_ = last_poll_ = next_frame_ = now_s();
  apply_script(1);
  // Something to look at before the first (possibly long) step. While training runs, this frame
  // leaves the renders of the side panels to the first budgeted frame: in a short run the
  // first frame is most of the viewer's share.
  first_frame_light_ = !paused_;
  draw_frame();
  first_frame_light_ = false;
}

TrainView::~TrainView() {
  try {
    close();
  } catch (const std::exception& e) { std::fprintf(stderr, "train --view: %s\n", e.what()); }
  display_.input().on_key = nullptr;
  display_.input().ui_mouse = display_.input().ui_keys = false;
}

// Training view v's pose as an orbit, aimed at the depth of the initial cloud's centre.
Orbit TrainView::view_orbit(uint32_t v) const {
  const Camera& cam = data_.train[v].camera;
  const auto c = cam.center();
  double depth = 0;
  for (int k = 0; k < 3; ++k) depth += (centre_.target[k] - c[k]) * cam.R[6 + k];
  if (!(depth > 0))
    depth = data_.near > 0 && data_.far > data_.near ? 0.5 * (data_.near + data_.far) : centre_.distance;
  return orbit_from_camera(cam, depth, frame_);
}

void TrainView::press(int key) {
  switch (key) {
    case GLFW_KEY_SPACE:
      paused_ = !paused_;
      step_requests_ = 0;
      break;
    case GLFW_KEY_N:
      if (!paused_)
        paused_ = true;
      else
        ++step_requests_;
      break;
    case GLFW_KEY_RIGHT:
    case GLFW_KEY_RIGHT_BRACKET:
      view_ = uint32_t((view_ + 1) % data_.train.size());
      break;
    case GLFW_KEY_LEFT:
    case GLFW_KEY_LEFT_BRACKET:
      view_ = uint32_t((view_ + data_.train.size() - 1) % data_.train.size());
      break;
    case GLFW_KEY_O:
      overlay_ = !overlay_;
      break;
    case GLFW_KEY_R:  // to the shown view's pose
      display_.input().orbit = home_ = view_orbit(view_);
      break;
    default:
      for (auto& p : panels_)
        if (p->key() == key) p->visible = !p->visible;
  }
}

void TrainView::apply_script(int frame) {
  auto it = script_.find(frame);
  if (it == script_.end()) return;
  for (const ScriptAction& a : it->second) {
    if (a.key)
      press(a.key);
    else
      pending_widgets_.push_back(a);
  }
}

void TrainView::poll() {
  glfwPollEvents();
  const double t = now_s();
  display_.fly(std::min(t - last_poll_, 0.1));
  last_poll_ = t;
  if (display_.should_close()) close();
}

void TrainView::before_step() {
  if (!open_) return;
  poll();
  auto interrupted = [&] { return interrupted_ && *interrupted_; };
  bool waited = false;
  while (open_ && paused_ && step_requests_ == 0 && !interrupted()) {
    waited = true;
    const double t = now_s();
    if (t >= next_frame_) {
      draw_frame();
    } else {
      glfwWaitEventsTimeout(std::min(next_frame_ - t, 0.1));
    }
    poll();
  }
  if (step_requests_ > 0) --step_requests_;
  // Time spent paused is neither training time nor charged to the budget.
  if (waited) last_mark_ = now_s();
}

void TrainView::after_step(const StepStats& st) {
  const double t = now_s();
  last_step_ = st.step;
  if (!st.skipped) {
    last_loss_ = st.loss;
    loss_ema_ = loss_ema_ < 0 ? st.loss : 0.9 * loss_ema_ + 0.1 * st.loss;
    loss_hist_.push_back(float(st.loss));
    term_hist_.resize(st.term_values.size());
    for (size_t i = 0; i < st.term_values.size(); ++i) term_hist_[i].push_back(float(st.term_values[i]));
  }
  if (!open_) return;
  // Credit: budget x wall time since the last mark (viewer time included: the share is of the
  // whole), capped so that a long stretch without frames does not buy a burst of them.
  training_wall_s_ += t - last_mark_;
  credit_ = std::min(credit_ + opt_.budget * (t - last_mark_), std::max(0.1, frame_cost_));
  if (last_step_time_ > 0) {
    const double its = 1.0 / std::max(t - last_step_time_, 1e-9);
    its_ema_ = its_ema_ > 0 ? 0.8 * its_ema_ + 0.2 * its : its;
  }
  last_step_time_ = t;
  last_mark_ = t;
  poll();
  if (!open_) return;
  const bool due = opt_.fps_cap <= 0 || t >= next_frame_;
  // A frame is drawn when the credit covers what frames have been costing, so that a short run
  // does not end in debt.
  if (paused_ || (credit_ >= frame_cost_ && due)) draw_frame();
}

void TrainView::after_training() {
  training_done_ = true;
  while (open_ && ((opt_.frames > 0 && frames_shown_ < opt_.frames) || opt_.hold)) {
    if (interrupted_ && *interrupted_) break;
    const double t = now_s();
    if (t >= next_frame_)
      draw_frame();
    else
      glfwWaitEventsTimeout(std::min(next_frame_ - t, 0.1));
    poll();
  }
  close();
}

// The shown view's inputs: its blurry image and its events.
void TrainView::load_view_inputs() {
  const io::View& view = data_.train[view_];
  const uint32_t W = view.camera.width, H = view.camera.height;
  shown_.view = view_;
  shown_.width = W;
  shown_.height = H;
  if (view.blurry.width != W || view.blurry.height != H)
    throw std::runtime_error("train --view: view '" + view.name + "': blurry image " +
                             std::to_string(view.blurry.width) + "x" + std::to_string(view.blurry.height) +
                             " differs from its camera's " + std::to_string(W) + "x" + std::to_string(H));
  shown_.blurry.ensure(size_t(W) * H * 3 * 4);
  shown_.blurry.write(encoded(io::planar_rgb(view.blurry)));  // the canvas shows sRGB values
  EventImage ev = event_image(data_, view_);
  shown_.events_w = ev.width;
  shown_.events_h = ev.height;
  shown_.events_pos = ev.positive;
  shown_.events_neg = ev.negative;
  shown_.has_events = ev.has_events;
  shown_.events.ensure(ev.rgb.size() * 4);
  shown_.events.write(ev.rgb);
  shown_.inputs_ready = true;
}

// Re-renders what the side panels show: the view's inputs when the view changed, the renders
// when the view changed or training advanced (at most every refresh_s while training runs).
void TrainView::refresh_content(bool renders) {
  const io::View& view = data_.train[view_];
  const bool new_view = !shown_.inputs_ready || shown_.view != view_;
  const uint32_t step = trainer_.current_step();
  const bool running = !paused_ && !training_done_;
  const bool stale = shown_.step != step && (!running || now_s() - last_refresh_ >= opt_.refresh_s);
  const bool new_interval = shown_.has_flow && shown_.interval != interval_;
  // A panel whose content is fetched only while it is shown, shown again.
  const bool missing =
      (panel_visible("ldi") && !shown_.has_ldi) || (panel_visible("residual") && !shown_.has_residuals);
  if (!new_view && !stale && !new_interval && shown_.u == u_ && !missing) return;
  const uint32_t W = view.camera.width, H = view.camera.height;
  const size_t n = size_t(W) * H * 3;
  if (new_view) load_view_inputs();
  if (!renders) return;
  const bool blur = trainer_.config().mode == TrainMode::Blur;
  if (new_view || stale || new_interval || missing || shown_.step == UINT32_MAX) load_snapshot(step);
  // The render panel: the virtual frame at u when there is one, else a render at u along the
  // view's trajectory (plain mode: the view's training camera).
  const auto at = std::find(shown_.times.begin(), shown_.times.end(), u_);
  std::vector<float> mid;
  if (at != shown_.times.end())
    mid = shown_.frames[size_t(at - shown_.times.begin())].read<float>(n);
  else if (blur)
    mid = trainer_.render(trainer_.trajectories()[view_].camera_at(u_));
  else
    mid = trainer_.render(trainer_.training_camera(view_));
  shown_.u = u_;
  shown_.mid.ensure(n * 4);
  shown_.mid.write(mid);
  const bool at_mid = !blur || u_ == 0.5;
  shown_.psnr_mid_sharp = view.sharp_mid && at_mid ? psnr(mid, encoded(io::planar_rgb(*view.sharp_mid))) : -1;
  for (auto& p : panels_) p->refresh(shown_);
}

// The exposure as training sees it, from the trainer: its frames, its image model, its target,
// the chosen interval's flow and warped events, and, while their panels are shown, the LDI
// frames and what the residual loss compares.
void TrainView::load_snapshot(uint32_t step) {
  const io::View& view = data_.train[view_];
  const size_t n = size_t(view.camera.width) * view.camera.height * 3;
  const uint32_t intervals = trainer_.flow_intervals();
  interval_ = std::min(interval_, intervals > 0 ? intervals - 1 : 0u);
  const ViewSnapshot snap =
      trainer_.snapshot(view_, intervals > 0 ? int(interval_) : -1, {panel_visible("ldi"), panel_visible("residual")});
  load_flow(snap);
  load_ldi(snap);
  load_residuals(snap);
  shown_.times = snap.frames.size() > 1 ? snap.times : std::vector<double>{};
  while (shown_.frames.size() < shown_.times.size())
    shown_.frames.emplace_back(ctx_, n * 4, "view_frame" + std::to_string(shown_.frames.size()));
  shown_.frames.resize(shown_.times.size());
  for (size_t i = 0; i < shown_.frames.size(); ++i) {
    shown_.frames[i].ensure(n * 4);
    cmd_.copy(*snap.frames[i], shown_.frames[i], n * 4);
  }
  cmd_.submit();
  shown_.psnr = psnr(snap.model, snap.target);
  shown_.step = step;
  last_refresh_ = now_s();
}

bool TrainView::panel_visible(const std::string& id) const {
  for (auto& p : panels_)
    if (p->id() == id) return p->visible;
  return false;
}

// The LDI panel's frames (linear light) encoded for the canvas.
void TrainView::load_ldi(const ViewSnapshot& snap) {
  shown_.has_ldi = !snap.ldi_frames.empty();
  std::vector<std::vector<float>> srgb;
  for (const auto& f : snap.ldi_frames) srgb.push_back(encoded(f));
  upload_all(ctx_, shown_.ldi_frames, srgb, "view_ldi_frame");
}

// The residual panel's signed images of what L_res compares (none when not fetched).
void TrainView::load_residuals(const ViewSnapshot& snap) {
  shown_.has_residuals = snap.has_residuals;
  const ResidualImages im = snap.has_residuals ? residual_images(snap.residuals) : ResidualImages{{}, 0};
  shown_.residual_frames = snap.residuals.frames;
  shown_.residual_scale = im.scale;
  upload_all(ctx_, shown_.residuals, im.tiles, "view_residual");
}

// The flow panels' images of the snapshot's interval.
void TrainView::load_flow(const ViewSnapshot& snap) {
  shown_.has_flow = snap.has_flow;
  shown_.has_warped = snap.has_flow && snap.flow.warped;
  if (!snap.has_flow) return;
  const FlowImages im = flow_images(snap.flow);
  shown_.interval = snap.flow.interval;
  shown_.intervals = snap.flow.intervals;
  shown_.flow_max_px = im.max_px;
  auto upload = [](gpu::Buffer& b, const std::vector<float>& v) {
    b.ensure(v.size() * 4);
    b.write(v);
  };
  upload(shown_.flow, im.flow);
  if (!shown_.has_warped) return;
  upload(shown_.measured, im.measured);
  upload(shown_.predicted, im.predicted);
}

// The free camera's view: rendered again when the camera moved, the size changed, or the splats
// changed (at most every refresh_s while training runs). While training runs it is rendered at
// no more than kFreeCameraPixels x the shown view's pixel count and enlarged by the blit;
// paused or done, at the size it is shown.
void TrainView::render_free_view(const Rect& m) {
  if (m.empty()) return;
  const bool running = !paused_ && !training_done_;
  const double budget_px = kFreeCameraPixels * double(shown_.width) * double(shown_.height);
  const double scale = running && budget_px > 0 ? std::min(1.0, std::sqrt(budget_px / (double(m.w) * m.h))) : 1.0;
  const uint32_t w = std::max(1u, uint32_t(std::lround(m.w * scale)));
  const uint32_t h = std::max(1u, uint32_t(std::lround(m.h * scale)));
  const Orbit& o = display_.input().orbit;
  const bool moved = o.target != free_orbit_.target || o.distance != free_orbit_.distance || o.yaw != free_orbit_.yaw ||
                     o.pitch != free_orbit_.pitch || o.fov_y_deg != free_orbit_.fov_y_deg;
  const uint32_t step = trainer_.current_step();
  const bool stale = step != free_step_ && (!running || now_s() - last_free_ >= opt_.refresh_s);
  if (!moved && !stale && w == free_w_ && h == free_h_) return;
  RenderSettings s;
  s.background = trainer_.config().background;
  s.antialiased = trainer_.config().antialiased;
  raster_.forward(trainer_.params(), orbit_camera(o, w, h), s, free_view_);
  free_orbit_ = o;
  free_step_ = step;
  free_w_ = w;
  free_h_ = h;
  last_free_ = now_s();
}

void TrainView::draw_frame() {
  const double t0 = now_s();
  const bool charged = !paused_ && !training_done_;  // frames while training runs count against the budget
  if (!display_.sync_swapchain()) {                  // minimised: nothing to draw
    next_frame_ = t0 + 0.1;
    return;
  }
  // Scripted widget actions use the widgets' rectangles from the last frame; they may change
  // the view, u or the panels, so they run before the content is refreshed.
  for (const ScriptAction& a : pending_widgets_) run_widget_action(a);
  pending_widgets_.clear();
  refresh_content(!first_frame_light_);
  const bool ok = present_frame(compose());
  const double t1 = now_s();
  (charged ? viewer_s_ : other_s_) += t1 - t0;
  if (charged) {
    credit_ -= t1 - t0;
    frame_cost_ = frame_cost_ > 0 ? 0.7 * frame_cost_ + 0.3 * (t1 - t0) : t1 - t0;
  }
  next_frame_ = opt_.fps_cap > 0 ? std::max(next_frame_ + 1.0 / opt_.fps_cap, t1) : t1;
  if (!ok) return;
  ++frames_shown_;
  std::vector<std::string> ids;  // the panels this frame showed
  for (auto& [id, placed] : last_tiles_) ids.push_back(id);
  frame_log_.push_back({{"frame", frames_shown_},
                        {"step", trainer_.current_step()},
                        {"paused", paused_},
                        {"view", view_},
                        {"content_step", shown_.step},
                        {"u", shown_.u},
                        {"panels", ids},
                        {"ms", 1000.0 * (t1 - t0)}});
  char title[256];
  std::snprintf(title, sizeof title, "evflow train - step %u/%u - %.2f it/s - view %u - %s", trainer_.current_step(),
                trainer_.config().iterations, its_ema_, view_ + 1, paused_ ? "paused" : "running");
  display_.set_title(title);
  if (opt_.frames > 0 && frames_shown_ >= opt_.frames) {
    close();
    return;
  }
  apply_script(frames_shown_ + 1);
}

// Draws the free camera and the visible panels' tiles on the canvas (submitted); returns each
// panel's label strip and text for the UI to write.
std::vector<std::pair<Rect, std::string>> TrainView::compose() {
  gpu::Swapchain& sc = display_.swapchain();
  const uint32_t W = sc.width(), H = sc.height();
  canvas_.resize(W, H, sc.bgr());
  std::vector<Panel*> shown;
  for (auto& p : panels_)
    if (p->visible && p->available(shown_)) shown.push_back(p.get());
  const TrainLayout layout = train_layout(W, H, uint32_t(shown.size()), uint32_t(ui_->font_size()) + 4);
  main_rect_ = layout.main;
  const Rect& m = layout.main;
  render_free_view(m);
  canvas_.fill({0, 0, W, H}, kBackground);
  if (!m.empty()) canvas_.blit(free_view_.outputs().rgb, free_w_, free_h_, m);
  last_tiles_.clear();
  std::vector<std::pair<Rect, std::string>> labels;
  for (size_t i = 0; i < shown.size(); ++i) {
    labels.push_back({layout.labels[i], shown[i]->label(shown_)});
    const std::vector<Tile> tiles = shown[i]->tiles(shown_);
    std::vector<std::pair<Rect, Tile>> placed;
    if (!tiles.empty()) {
      const std::vector<Rect> rects =
          tile_grid(layout.boxes[i], uint32_t(tiles.size()), tiles[0].width, tiles[0].height, 2, shown[i]->group());
      for (size_t k = 0; k < rects.size() && k < tiles.size(); ++k) {
        canvas_.blit(*tiles[k].rgb, tiles[k].width, tiles[k].height, rects[k]);
        placed.push_back({rects[k], tiles[k]});
      }
    }
    last_tiles_.push_back({shown[i]->id(), std::move(placed)});
  }
  cmd_.submit();
  return labels;
}

// Runs the UI, presents the canvas with the UI drawn over it (read back when a screenshot is
// due) and writes the screenshot the button asked for. False when nothing was presented.
bool TrainView::present_frame(const std::vector<std::pair<Rect, std::string>>& labels) {
  ui_->begin();
  build_ui(labels);
  ui_->end();
  display_.input().ui_mouse = ui_->wants_mouse();
  display_.input().ui_keys = ui_->wants_keys();
  gpu::Swapchain& sc = display_.swapchain();
  const bool capture = shot_requested_ || !opt_.screenshot.empty();
  if (capture) readback_.ensure(uint64_t(sc.width()) * sc.height() * 4);
  const bool ok = sc.present(
      canvas_.packed(), [this](VkCommandBuffer cb) { ui_->draw(cb); }, capture ? &readback_ : nullptr);
  if (ok && shot_requested_) {
    shot_requested_ = false;
    char name[64];
    std::snprintf(name, sizeof name, "view-step%06u-%d.png", trainer_.current_step(), ++shots_);
    last_shot_ = (std::filesystem::path(opt_.shot_dir) / name).string();
    save_frame(last_shot_);
  }
  return ok;
}

// The presented frame with the UI (read back by the last present) as an 8-bit PNG, written
// atomically (a temporary, then a rename).
void TrainView::save_frame(const std::string& path) {
  const uint32_t W = display_.swapchain().width(), H = display_.swapchain().height();
  const std::vector<uint32_t> px = readback_.read<uint32_t>(size_t(W) * H);
  std::vector<uint8_t> rgb(px.size() * 3);
  const bool bgr = display_.swapchain().bgr();
  for (size_t i = 0; i < px.size(); ++i) {
    const uint8_t c0 = px[i] & 0xFF, c1 = (px[i] >> 8) & 0xFF, c2 = (px[i] >> 16) & 0xFF;
    rgb[i * 3 + 0] = bgr ? c2 : c0;
    rgb[i * 3 + 1] = c1;
    rgb[i * 3 + 2] = bgr ? c0 : c2;
  }
  io::write_png8(path, W, H, 3, rgb);
}

nlohmann::json TrainView::report() const {
  using nlohmann::json;
  auto rect = [](const Rect& r) { return json{{"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h}}; };
  json panels = json::array();
  for (auto& [id, placed] : last_tiles_) {
    json tiles = json::array();
    for (auto& [r, t] : placed) {
      json j = rect(r);
      j["src_w"] = t.width;
      j["src_h"] = t.height;
      tiles.push_back(j);
    }
    panels.push_back({{"id", id}, {"tiles", tiles}});
  }
  json weights = json::object();
  for (const LossTerm* t : trainer_.losses()) weights[t->name()] = t->weight();
  json widgets = json::object();
  for (auto& [name, r] : ui_->widgets()) widgets[name] = {{"x", r.x}, {"y", r.y}, {"w", r.w}, {"h", r.h}};
  return json{
      {"canvas", {canvas_.width(), canvas_.height()}},
      {"main", rect(main_rect_)},
      {"panels", panels},
      {"frames", frame_log_},
      {"content",
       {{"view", shown_.view},
        {"step", shown_.step},
        {"psnr", shown_.psnr},
        {"psnr_mid_sharp", shown_.psnr_mid_sharp},
        {"events_pos", shown_.events_pos},
        {"events_neg", shown_.events_neg},
        {"virtual_times", shown_.times},
        {"flow",
         {{"shown", shown_.has_flow},
          {"warped", shown_.has_warped},
          {"interval", shown_.interval},
          {"intervals", shown_.intervals},
          {"max_px", shown_.flow_max_px}}},
        {"ldi", {{"shown", shown_.has_ldi}, {"frames", shown_.ldi_frames.size()}}},
        {"residual",
         {{"shown", shown_.has_residuals}, {"frames", shown_.residual_frames}, {"scale", shown_.residual_scale}}}}},
      {"u", u_},
      {"weights", weights},
      {"widgets", widgets},
      {"screenshots", shots_},
      {"last_screenshot", last_shot_},
      {"viewer_seconds", viewer_s_},
      {"viewer_seconds_untimed", other_s_},
      {"training_wall_seconds", training_wall_s_},
      {"budget", opt_.budget}};
}

void TrainView::close() {
  if (!open_) return;
  open_ = false;
  paused_ = false;
  step_requests_ = 0;
  if (!opt_.screenshot.empty()) {
    if (frames_shown_ == 0) throw std::runtime_error("train --view: no frame was presented, no screenshot written");
    save_frame(opt_.screenshot);
    std::fprintf(stderr, "train --view: %d frame(s) presented, wrote %s (%ux%u)\n", frames_shown_,
                 opt_.screenshot.c_str(), canvas_.width(), canvas_.height());
  }
  if (!opt_.report.empty()) {
    std::ofstream f(opt_.report);
    f << report().dump(1) << "\n";
    if (!f) throw std::runtime_error(opt_.report + ": cannot write the viewer report");
  }
  std::fprintf(stderr,
               "train --view: viewer closed after %d frame(s); its time %.2f s of %.2f s training wall time (%.1f%%), "
               "%.2f s more while paused or after training%s\n",
               frames_shown_, viewer_s_, training_wall_s_,
               training_wall_s_ > 0 ? 100.0 * viewer_s_ / training_wall_s_ : 0.0, other_s_,
               training_done_ ? "" : "; training goes on");
  glfwHideWindow(display_.window());
  glfwPollEvents();
}

}  // namespace evflow::viewer
