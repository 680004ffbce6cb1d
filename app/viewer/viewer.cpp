#include "viewer/viewer.h"

// Vulkan before GLFW so that glfwCreateWindowSurface is declared.
#include <vulkan/vulkan.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "gpu/swapchain.h"
#include "io/image.h"
#include "splat/rasterizer.h"
#include "viewer/view_camera.h"

namespace evflow::viewer {

namespace {

using Clock = std::chrono::steady_clock;

struct PackPC {
  uint32_t width, height, bgr;
};

struct Input {
  Orbit orbit;
  bool dragging = false;
  double last_x = 0, last_y = 0;
  double scroll = 0;
  bool changed = true;
};

struct GlfwSession {
  GlfwSession() {
    glfwSetErrorCallback([](int code, const char* msg) { std::fprintf(stderr, "evflow view: GLFW error %d: %s\n", code, msg); });
    if (!glfwInit())
      throw std::runtime_error("evflow view: cannot open a window (GLFW could not initialise: is DISPLAY set? "
                               "headless machines can use xvfb-run)");
  }
  ~GlfwSession() { glfwTerminate(); }
};

struct Window {
  GLFWwindow* w = nullptr;
  Window(uint32_t width, uint32_t height, const std::string& title) {
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    w = glfwCreateWindow(int(width), int(height), title.c_str(), nullptr, nullptr);
    if (!w) throw std::runtime_error("evflow view: glfwCreateWindow failed");
  }
  ~Window() { glfwDestroyWindow(w); }
};

Input& input_of(GLFWwindow* w) { return *static_cast<Input*>(glfwGetWindowUserPointer(w)); }

void install_callbacks(GLFWwindow* w) {
  glfwSetMouseButtonCallback(w, [](GLFWwindow* win, int button, int action, int) {
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    Input& in = input_of(win);
    in.dragging = action == GLFW_PRESS;
    glfwGetCursorPos(win, &in.last_x, &in.last_y);
  });
  glfwSetCursorPosCallback(w, [](GLFWwindow* win, double x, double y) {
    Input& in = input_of(win);
    if (!in.dragging) return;
    int fw = 0, fh = 0;
    glfwGetWindowSize(win, &fw, &fh);
    orbit_rotate(in.orbit, x - in.last_x, y - in.last_y, uint32_t(std::max(fh, 1)));
    in.last_x = x;
    in.last_y = y;
    in.changed = true;
  });
  glfwSetScrollCallback(w, [](GLFWwindow* win, double, double dy) {
    Input& in = input_of(win);
    orbit_zoom(in.orbit, dy);
    in.changed = true;
  });
  glfwSetKeyCallback(w, [](GLFWwindow* win, int key, int, int action, int) {
    if (action == GLFW_PRESS && key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(win, GLFW_TRUE);
  });
}

// WASD/QE: flies at half the orbit distance per second.
void fly(GLFWwindow* w, Input& in, double dt) {
  auto key = [&](int k) { return glfwGetKey(w, k) == GLFW_PRESS ? 1.0 : 0.0; };
  const double right = key(GLFW_KEY_D) - key(GLFW_KEY_A);
  const double forward = key(GLFW_KEY_W) - key(GLFW_KEY_S);
  const double down = key(GLFW_KEY_Q) - key(GLFW_KEY_E);  // E up, Q down
  if (right == 0 && forward == 0 && down == 0) return;
  const double speed = 0.5 * dt;
  orbit_fly(in.orbit, right * speed, down * speed, forward * speed);
  in.changed = true;
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

}  // namespace

int run_viewer(const GaussianCloud& cloud, const ViewerOptions& opt) {
  GlfwSession glfw;
  if (!glfwVulkanSupported()) throw std::runtime_error("evflow view: GLFW found no Vulkan loader with surface support");
  uint32_t n_ext = 0;
  const char** exts = glfwGetRequiredInstanceExtensions(&n_ext);
  if (!exts) throw std::runtime_error("evflow view: GLFW reports no Vulkan surface extensions for this display");
  gpu::ContextOptions copts = opt.context;
  copts.presentation = true;
  copts.instance_extensions.assign(exts, exts + n_ext);

  Window window(opt.width, opt.height, opt.title);
  Input input;
  input.orbit = initial_orbit(cloud);
  glfwSetWindowUserPointer(window.w, &input);
  install_callbacks(window.w);

  gpu::Context ctx(copts);
  std::vector<std::string> problems;
  {
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    gpu::check(glfwCreateWindowSurface(ctx.instance(), window.w, nullptr, &surface), "glfwCreateWindowSurface");
    int fbw = 0, fbh = 0;
    glfwGetFramebufferSize(window.w, &fbw, &fbh);
    gpu::Swapchain sc(ctx, surface, uint32_t(fbw), uint32_t(fbh), opt.vsync);
    std::fprintf(stderr, "evflow view: %s, %s, %zu Gaussians\n", ctx.caps().name.c_str(), sc.describe().c_str(), cloud.size());

    GaussianBuffers params(ctx, cloud.size(), cloud.sh_degree, "view");
    params.upload(cloud);
    Rasterizer raster(ctx);
    gpu::Commands cmd(ctx);
    gpu::Buffer packed(ctx, uint64_t(std::max(sc.width(), 1u)) * std::max(sc.height(), 1u) * 4, "view_rgba8");
    RenderSettings settings;

    const double frame_s = opt.fps_cap > 0 ? 1.0 / opt.fps_cap : 0.0;
    auto last_title = Clock::now(), last_tick = Clock::now(), next_frame = Clock::now();
    int shown = 0, since_title = 0;
    double render_ms_sum = 0;
    bool last_valid = false;
    uint32_t last_w = 0, last_h = 0;
    const bool resize_test = opt.resize_width > 0 && opt.resize_height > 0;
    bool resize_requested = false;
    int iterations = 0;
    while (!glfwWindowShouldClose(window.w)) {
      glfwPollEvents();
      auto now = Clock::now();
      const double dt = std::chrono::duration<double>(now - last_tick).count();
      last_tick = now;
      fly(window.w, input, std::min(dt, 0.1));

      glfwGetFramebufferSize(window.w, &fbw, &fbh);
      if (sc.needs_recreate() || uint32_t(fbw) != sc.width() || uint32_t(fbh) != sc.height()) {
        if (fbw > 0 && fbh > 0) sc.recreate(uint32_t(fbw), uint32_t(fbh));
        else if (sc.ready()) sc.recreate(0, 0);
      }
      if (!sc.ready()) {  // minimised
        glfwWaitEventsTimeout(0.1);
        continue;
      }
      const uint32_t w = sc.width(), h = sc.height();
      packed.ensure(uint64_t(w) * h * 4);

      const auto t0 = Clock::now();
      const Camera cam = orbit_camera(input.orbit, w, h);
      raster.forward(params, cam, settings);
      PackPC pc{w, h, sc.bgr() ? 1u : 0u};
      cmd.dispatch("view/pack_rgba8", {raster.outputs().rgb, packed}, pc, cmd.linear_groups(gpu::Commands::div_up(uint64_t(w) * h, 256)));
      cmd.submit();
      const bool ok = sc.present(packed);
      render_ms_sum += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      input.changed = false;
      if (ok) {
        ++shown;
        ++since_title;
        last_valid = true;
        last_w = w;
        last_h = h;
      }
      if (resize_test && !resize_requested && shown >= 2) {
        glfwSetWindowSize(window.w, int(opt.resize_width), int(opt.resize_height));
        resize_requested = true;
      }
      const bool resized = !resize_test || (w == opt.resize_width && h == opt.resize_height);
      if (opt.frames > 0 && shown >= opt.frames && resized) break;
      if (opt.frames > 0 && ++iterations > 20 * opt.frames + 200)
        throw std::runtime_error("evflow view: " + std::to_string(iterations) + " frames without reaching --frames " +
                                 std::to_string(opt.frames) + (resize_test ? " at the --resize-to size" : ""));

      now = Clock::now();
      const double since = std::chrono::duration<double>(now - last_title).count();
      if (since >= 0.5) {
        char title[256];
        std::snprintf(title, sizeof title, "%s - %zu Gaussians - %.1f fps (%.1f ms/frame) - %ux%u", opt.title.c_str(),
                      cloud.size(), since_title / since, since_title ? render_ms_sum / since_title : 0.0, w, h);
        glfwSetWindowTitle(window.w, title);
        last_title = now;
        since_title = 0;
        render_ms_sum = 0;
      }
      if (frame_s > 0) {
        next_frame += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(frame_s));
        if (next_frame < now) next_frame = now;  // behind: don't try to catch up
        std::this_thread::sleep_until(next_frame);
      }
    }
    if (!opt.screenshot.empty()) {
      if (!last_valid) throw std::runtime_error("evflow view: no frame was presented, no screenshot written");
      save_screenshot(packed, last_w, last_h, sc.bgr(), opt.screenshot);
      std::fprintf(stderr, "evflow view: %d frame(s) presented, wrote %s (%ux%u)\n", shown, opt.screenshot.c_str(), last_w, last_h);
    }
  }
  problems = ctx.take_validation_messages();
  if (!problems.empty()) {
    for (const auto& m : problems) std::fprintf(stderr, "%s\n", m.c_str());
    std::fprintf(stderr, "evflow view: %zu validation message(s) reported\n", problems.size());
    return 3;
  }
  return 0;
}

}  // namespace evflow::viewer
