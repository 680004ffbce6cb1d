// The ImGui side of `evflow train --view`: the training window (statistics, loss plots, pause /
// step / view / u / panel / screenshot controls, live loss weights) and the panels' labels, plus
// the scripted widget actions that tests use (docs/viewer.md).
#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "viewer/train_view.h"

namespace evflow::viewer {

namespace {

constexpr int kPlotPoints = 400;  // the plots show the last this many steps
constexpr float kPlotHeight = 42.0f;

// The last kPlotPoints values of `v` as a PlotLines with its newest value as overlay text.
void plot(const char* id, const std::vector<float>& v) {
  const int n = int(std::min<size_t>(v.size(), kPlotPoints));
  char overlay[64] = "";
  if (n > 0) std::snprintf(overlay, sizeof overlay, "%.5f", v.back());
  ImGui::PlotLines(id, n ? v.data() + (v.size() - size_t(n)) : nullptr, n, 0, overlay, FLT_MAX, FLT_MAX,
                   ImVec2(ImGui::GetContentRegionAvail().x, kPlotHeight));
}

}  // namespace

void TrainView::build_ui(const std::vector<std::pair<Rect, std::string>>& labels) {
  // Panel labels: text on the label strips above the panels, clipped to the strip.
  ImDrawList* bg = ImGui::GetBackgroundDrawList();
  for (const auto& [r, text] : labels) {
    const ImVec4 clip(float(r.x), float(r.y), float(r.x + r.w), float(r.y + r.h));
    bg->AddText(ImGui::GetFont(), ImGui::GetFontSize(), ImVec2(float(r.x) + 3, float(r.y) + 2),
                IM_COL32(230, 230, 230, 255), text.c_str(), nullptr, 0.0f, &clip);
  }
  if (!overlay_ || main_rect_.empty()) return;
  const Rect& m = main_rect_;
  const float pad = 6.0f;
  ImGui::SetNextWindowPos(ImVec2(float(m.x) + pad, float(m.y) + pad), ImGuiCond_Always);
  const float w = std::max(std::min(360.0f, float(m.w) - 2 * pad), 1.0f);
  ImGui::SetNextWindowSizeConstraints(ImVec2(w, 0), ImVec2(w, std::max(float(m.h) - 2 * pad, 1.0f)));
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("evflow train", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
  build_stats();
  build_controls();
  build_weights();
  ui_->track_window("window");
  ImGui::End();
}

void TrainView::build_stats() {
  const TrainConfig& cfg = trainer_.config();
  const double share = training_wall_s_ > 0 ? viewer_s_ / training_wall_s_ : 0.0;
  ImGui::Text("step %u / %u  %s", trainer_.current_step(), cfg.iterations,
              training_done_ ? "done"
              : paused_      ? "paused"
                             : "running");
  ImGui::Text("loss %.5f   %.2f it/s", loss_ema_ < 0 ? 0.0 : loss_ema_, its_ema_);
  ImGui::Text("Gaussians %zu   viewer %.1f%% of wall time", trainer_.params().count, 100.0 * share);
  const io::View& view = data_.train[view_];
  ImGui::Text("view %u/%zu %s   PSNR %.2f dB", view_ + 1, data_.train.size(), view.name.c_str(), shown_.psnr);
  if (shown_.psnr_mid_sharp >= 0) ImGui::Text("mid render vs sharp %.2f dB", shown_.psnr_mid_sharp);
  ImGui::Checkbox("loss plots", &plots_);
  ui_->track("plots");
  if (!plots_) return;
  plot("##loss", loss_hist_);
  ImGui::TextUnformatted("total loss");
  const auto& terms = trainer_.losses();
  for (size_t i = 0; i < terms.size() && i < term_hist_.size(); ++i) {
    plot(("##term" + std::to_string(i)).c_str(), term_hist_[i]);
    ImGui::Text("%s (unweighted)", terms[i]->name().c_str());
  }
}

void TrainView::build_controls() {
  ImGui::Separator();
  if (ImGui::Button(paused_ ? "Resume" : "Pause")) press(GLFW_KEY_SPACE);
  ui_->track("pause");
  ImGui::SameLine();
  if (ImGui::Button("Step")) press(GLFW_KEY_N);
  ui_->track("step");
  ImGui::SameLine();
  if (ImGui::Button("Screenshot")) shot_requested_ = true;
  ui_->track("screenshot");
  if (!last_shot_.empty()) {
    ImGui::SameLine();
    ImGui::TextUnformatted("saved");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", last_shot_.c_str());
  }

  if (ImGui::Button("<")) press(GLFW_KEY_LEFT);
  ui_->track("view.prev");
  ImGui::SameLine();
  const int n_views = int(data_.train.size());
  int v = int(view_);
  const float slider_w = ImGui::GetContentRegionAvail().x - 2 * ImGui::GetFrameHeight() - 8;
  ImGui::SetNextItemWidth(std::max(slider_w, 40.0f));
  if (ImGui::SliderInt("##view", &v, 0, n_views - 1, "view %d")) request_view(uint32_t(std::clamp(v, 0, n_views - 1)));
  ui_->track("view", UiLayer::slider_grab(ImGui::GetItemRectSize().x, n_views - 1));
  ImGui::SameLine();
  if (ImGui::Button(">")) press(GLFW_KEY_RIGHT);
  ui_->track("view.next");
  if (ImGui::Button("Camera to view")) press(GLFW_KEY_R);
  ui_->track("camera");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("the free camera jumps to the shown training view's pose (R)");

  if (trainer_.config().mode == TrainMode::Blur) {
    float u = float(u_);
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x);
    if (ImGui::SliderFloat("##u", &u, 0.0f, 1.0f, "exposure u = %.3f")) u_ = std::clamp(double(u), 0.0, 1.0);
    ui_->track("u", UiLayer::slider_grab(ImGui::GetItemRectSize().x));
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("the render panel shows the view at time u of its learned exposure trajectory");
  }

  const int intervals = int(trainer_.flow_intervals());
  if (intervals > 0) {
    int i = int(interval_);
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x);
    if (ImGui::SliderInt("##interval", &i, 0, intervals - 1, "flow interval i = %d"))
      interval_ = uint32_t(std::clamp(i, 0, intervals - 1));
    ui_->track("interval", UiLayer::slider_grab(ImGui::GetItemRectSize().x, intervals - 1));
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("the flow and warped-event panels show interval i, from virtual frame i to i + 1");
  }

  ImGui::TextUnformatted("panels");
  for (size_t k = 0; k < panels_.size(); ++k) {
    if (k % 4 != 0 || k == 0) ImGui::SameLine();  // four to a line: the window is narrow
    ImGui::Checkbox(panels_[k]->id().c_str(), &panels_[k]->visible);
    ui_->track("panel." + panels_[k]->id());
  }
}

// One slider per loss term, writing the trainer's weight: the next step uses it.
void TrainView::build_weights() {
  const auto& terms = trainer_.losses();
  if (weight_max_.size() != terms.size()) {
    weight_max_.clear();
    for (const LossTerm* t : terms) weight_max_.push_back(std::max(1.0f, 2.0f * t->weight()));
  }
  ImGui::Separator();
  ImGui::TextUnformatted("loss weights");
  for (size_t i = 0; i < terms.size(); ++i) {
    float w = terms[i]->weight();
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.6f);
    if (ImGui::SliderFloat(("##w" + std::to_string(i)).c_str(), &w, 0.0f, weight_max_[i], "%.3f"))
      terms[i]->set_weight(std::max(w, 0.0f));
    ui_->track("weight." + terms[i]->name(), UiLayer::slider_grab(ImGui::GetItemRectSize().x));
    ImGui::SameLine();
    ImGui::TextUnformatted(terms[i]->name().c_str());
  }
}

void TrainView::request_view(uint32_t v) {
  if (v < data_.train.size()) view_ = v;
}

// Presses the left button over the named widget through ImGui's input: a frame hovering, one
// pressing, one releasing, each running the UI (not presented). Each frame aims at the widget's
// rectangle as the frame before drew it (the first at the last presented frame's), so a layout
// that settles (a scroll bar appearing) is followed.
void TrainView::run_widget_action(const ScriptAction& a) {
  for (bool down : {false, true, false}) {
    const auto& w = ui_->widgets();
    const auto it = w.find(a.widget);
    if (it == w.end()) {
      std::string known;
      for (auto& [name, r] : w) known += (known.empty() ? "" : ", ") + name;
      throw std::runtime_error("--view-script: no widget '" + a.widget + "' on screen (widgets: " + known + ")");
    }
    ui_->script_pointer(it->second.press_x(a.at), it->second.y + 0.5f * it->second.h, down);
    ui_->begin();
    build_ui({});
    ui_->discard();
  }
  ui_->release_pointer();
}

}  // namespace evflow::viewer
