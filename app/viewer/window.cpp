#include "viewer/window.h"

#include <cstdio>
#include <stdexcept>

#include "io/image.h"

namespace evflow::viewer {

namespace {

Input& input_of(GLFWwindow* w) { return *static_cast<Input*>(glfwGetWindowUserPointer(w)); }

void install_callbacks(GLFWwindow* w) {
  glfwSetMouseButtonCallback(w, [](GLFWwindow* win, int button, int action, int) {
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    Input& in = input_of(win);
    in.dragging = action == GLFW_PRESS && !in.ui_mouse;
    glfwGetCursorPos(win, &in.last_x, &in.last_y);
  });
  glfwSetCursorPosCallback(w, [](GLFWwindow* win, double x, double y) {
    Input& in = input_of(win);
    if (!in.dragging) return;
    int ww = 0, wh = 0;
    glfwGetWindowSize(win, &ww, &wh);
    orbit_rotate(in.orbit, x - in.last_x, y - in.last_y, uint32_t(std::max(wh, 1)));
    in.last_x = x;
    in.last_y = y;
  });
  glfwSetScrollCallback(w, [](GLFWwindow* win, double, double dy) {
    Input& in = input_of(win);
    if (!in.ui_mouse) orbit_zoom(in.orbit, dy);
  });
  glfwSetKeyCallback(w, [](GLFWwindow* win, int key, int, int action, int mods) {
    if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
    if (key == GLFW_KEY_ESCAPE) {
      if (action == GLFW_PRESS) glfwSetWindowShouldClose(win, GLFW_TRUE);
      return;
    }
    Input& in = input_of(win);
    if (in.on_key && !in.ui_keys) in.on_key(key, mods);
  });
}

}  // namespace

Display::Glfw::Glfw(const std::string& what) {
  glfwSetErrorCallback(
      [](int code, const char* msg) { std::fprintf(stderr, "evflow: GLFW error %d: %s\n", code, msg); });
  if (!glfwInit())
    throw std::runtime_error(what +
                             ": cannot open a window (GLFW could not initialise: is DISPLAY set? "
                             "headless machines can use xvfb-run)");
}
Display::Glfw::~Glfw() { glfwTerminate(); }

Display::Display(const std::string& what, uint32_t width, uint32_t height, const std::string& title,
                 gpu::ContextOptions copts, bool vsync)
    : glfw_(what), what_(what) {
  if (!glfwVulkanSupported()) throw std::runtime_error(what + ": GLFW found no Vulkan loader with surface support");
  uint32_t n_ext = 0;
  const char** exts = glfwGetRequiredInstanceExtensions(&n_ext);
  if (!exts) throw std::runtime_error(what + ": GLFW reports no Vulkan surface extensions for this display");
  copts.presentation = true;
  copts.instance_extensions.assign(exts, exts + n_ext);

  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  window_ = glfwCreateWindow(int(width), int(height), title.c_str(), nullptr, nullptr);
  if (!window_) throw std::runtime_error(what + ": glfwCreateWindow failed");
  glfwSetWindowUserPointer(window_, &input_);
  install_callbacks(window_);
  try {
    ctx_ = std::make_unique<gpu::Context>(copts);
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    gpu::check(glfwCreateWindowSurface(ctx_->instance(), window_, nullptr, &surface), "glfwCreateWindowSurface");
    int fbw = 0, fbh = 0;
    glfwGetFramebufferSize(window_, &fbw, &fbh);
    sc_ = std::make_unique<gpu::Swapchain>(*ctx_, surface, uint32_t(fbw), uint32_t(fbh), vsync);
  } catch (...) {
    sc_.reset();
    ctx_.reset();
    glfwDestroyWindow(window_);
    throw;
  }
}

Display::~Display() {
  sc_.reset();
  ctx_.reset();
  glfwDestroyWindow(window_);
}

bool Display::sync_swapchain() {
  int fbw = 0, fbh = 0;
  glfwGetFramebufferSize(window_, &fbw, &fbh);
  if (sc_->needs_recreate() || uint32_t(fbw) != sc_->width() || uint32_t(fbh) != sc_->height()) {
    if (fbw > 0 && fbh > 0)
      sc_->recreate(uint32_t(fbw), uint32_t(fbh));
    else if (sc_->ready())
      sc_->recreate(0, 0);
  }
  return sc_->ready();
}

void Display::fly(double dt) {
  if (input_.ui_keys) return;
  auto key = [&](int k) { return glfwGetKey(window_, k) == GLFW_PRESS ? 1.0 : 0.0; };
  const double right = key(GLFW_KEY_D) - key(GLFW_KEY_A);
  const double forward = key(GLFW_KEY_W) - key(GLFW_KEY_S);
  const double down = key(GLFW_KEY_Q) - key(GLFW_KEY_E);  // E up, Q down
  if (right == 0 && forward == 0 && down == 0) return;
  const double speed = 0.5 * dt;  // half the orbit distance per second
  orbit_fly(input_.orbit, right * speed, down * speed, forward * speed);
}

void save_screenshot(const gpu::Buffer& packed, uint32_t w, uint32_t h, bool bgr, const std::string& path) {
  std::vector<uint32_t> px = packed.read<uint32_t>(size_t(w) * h);
  float lut[256];
  for (int i = 0; i < 256; ++i) lut[i] = io::srgb_to_linear(float(i) / 255.f);
  io::Image im(w, h, 3);
  for (size_t i = 0; i < px.size(); ++i) {
    uint32_t r = px[i] & 0xFF, g = (px[i] >> 8) & 0xFF, b = (px[i] >> 16) & 0xFF;
    if (bgr) std::swap(r, b);
    im.data[i * 3 + 0] = lut[r];
    im.data[i * 3 + 1] = lut[g];
    im.data[i * 3 + 2] = lut[b];
  }
  io::write_png(path, im);  // re-encodes to the same 8-bit values
}

int report_validation(gpu::Context& ctx, const std::string& what) {
  const std::vector<std::string> problems = ctx.take_validation_messages();
  if (problems.empty()) return 0;
  for (const auto& m : problems) std::fprintf(stderr, "%s\n", m.c_str());
  std::fprintf(stderr, "%s: %zu validation message(s) reported\n", what.c_str(), problems.size());
  return 3;
}

}  // namespace evflow::viewer
