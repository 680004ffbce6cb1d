// The window side shared by `evflow view` and `evflow train --view`: GLFW set-up, a Vulkan
// context with presentation on, the window's swapchain, orbit/fly mouse and key input, and
// screenshots of the presented canvas (docs/viewer.md).
#pragma once
// Vulkan before GLFW so that glfwCreateWindowSurface is declared.
#include <vulkan/vulkan.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <functional>
#include <memory>
#include <string>

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/swapchain.h"
#include "viewer/view_camera.h"

namespace evflow::viewer {

// Mouse and keyboard state of a window. Left drag orbits, the wheel zooms; keys other than Esc
// (which closes the window) go to on_key (GLFW key code, modifiers).
struct Input {
  Orbit orbit;
  bool dragging = false;
  double last_x = 0, last_y = 0;
  std::function<void(int key, int mods)> on_key;
  // Set by a UI drawn in the window while it uses the mouse / keyboard: the camera and on_key
  // then leave them alone.
  bool ui_mouse = false, ui_keys = false;
};

// GLFW, one window, a presentation-capable gpu::Context and the window's swapchain. Members are
// destroyed in reverse order: swapchain (and surface), context, window, GLFW.
class Display {
 public:
  // `what` names the command in error messages ("evflow view"). Throws std::runtime_error when
  // no window can be opened (no display, no Vulkan surface support).
  Display(const std::string& what, uint32_t width, uint32_t height, const std::string& title,
          gpu::ContextOptions options, bool vsync);
  ~Display();
  Display(const Display&) = delete;
  Display& operator=(const Display&) = delete;

  gpu::Context& context() { return *ctx_; }
  gpu::Swapchain& swapchain() { return *sc_; }
  GLFWwindow* window() const { return window_; }
  Input& input() { return input_; }
  bool should_close() const { return glfwWindowShouldClose(window_) != 0; }
  void set_title(const std::string& t) { glfwSetWindowTitle(window_, t.c_str()); }

  // Rebuilds the swapchain when the framebuffer size changed (or the last present said so).
  // Returns false while the window is minimised (no swapchain).
  bool sync_swapchain();
  // W/A/S/D/Q/E flying for `dt` seconds (keys held now).
  void fly(double dt);

 private:
  struct Glfw {
    explicit Glfw(const std::string& what);
    ~Glfw();
  } glfw_;
  std::string what_;
  GLFWwindow* window_ = nullptr;
  Input input_;
  std::unique_ptr<gpu::Context> ctx_;
  std::unique_ptr<gpu::Swapchain> sc_;
};

// Writes the packed canvas (w x h, byte order per bgr) as an 8-bit PNG.
void save_screenshot(const gpu::Buffer& packed, uint32_t w, uint32_t h, bool bgr, const std::string& path);

// Prints the context's validation messages; returns 3 when there were any, else 0.
int report_validation(gpu::Context& ctx, const std::string& what);

}  // namespace evflow::viewer
