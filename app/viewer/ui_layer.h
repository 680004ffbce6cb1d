// Dear ImGui on the viewer's window: the GLFW backend for input, the Vulkan backend drawing in
// the swapchain's render pass over the compute-made frame (docs/viewer.md). Also the scripted
// pointer used by tests: a widget's rectangle is recorded by name when it is drawn, and a
// scripted click or slider set presses the left button over it.
#pragma once
#include <map>
#include <string>

#include "viewer/window.h"

struct ImGuiContext;

namespace evflow::viewer {

struct UiRect {
  float x = 0, y = 0, w = 0, h = 0;
  float grab = 0;  // sliders: the grab's width (a press at a fraction of the range lands here)
  // Where to press so that a slider (with `grab`) moves to fraction f of its range; buttons and
  // check boxes: the centre (f < 0).
  float press_x(double f) const;
};

class UiLayer {
 public:
  // Needs the display's swapchain to be able to draw over frames (throws otherwise) and the
  // context's queue to support graphics. Installs ImGui's GLFW callbacks after the display's.
  explicit UiLayer(Display& display);
  ~UiLayer();
  UiLayer(const UiLayer&) = delete;
  UiLayer& operator=(const UiLayer&) = delete;

  // One UI frame: begin() (backends' new frame, then the scripted pointer if any), the
  // caller's ImGui calls, then end() (ImGui::Render) before the frame is presented; a frame
  // that is not presented ends with discard() instead.
  void begin();
  void end();
  void discard();
  // Records the last end()'s draw data (inside the swapchain's render pass).
  void draw(VkCommandBuffer cb);

  // Remembers the last drawn widget's rectangle under `name` (for scripted input and reports).
  void track(const std::string& name, float grab = 0);
  void track_window(const std::string& name);  // the current window's rectangle
  // The grab width of a slider as wide as `width` over `steps` integer values (0: a float slider).
  static float slider_grab(float width, int steps = 0);
  const std::map<std::string, UiRect>& widgets() const { return widgets_; }
  // While set, the next begin() puts the pointer at (x, y) with the left button down or up.
  void script_pointer(float x, float y, bool down);
  void release_pointer() { scripted_ = false; }
  // True while the UI uses the mouse or keyboard (then the free camera ignores them).
  bool wants_mouse() const;
  bool wants_keys() const;
  float font_size() const;  // pixels: the height of a line of UI text

 private:
  void shutdown();
  Display& display_;
  ImGuiContext* imgui_ = nullptr;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  bool glfw_ready_ = false, vulkan_ready_ = false;
  bool scripted_ = false, down_ = false;
  float px_ = 0, py_ = 0;
  std::map<std::string, UiRect> widgets_;
};

}  // namespace evflow::viewer
