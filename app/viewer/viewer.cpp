#include "viewer/viewer.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "splat/rasterizer.h"
#include "view/view_layout.h"
#include "viewer/view_camera.h"
#include "viewer/window.h"

namespace evflow::viewer {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

int run_viewer(const GaussianCloud& cloud, const ViewerOptions& opt) {
  Display display("evflow view", opt.width, opt.height, opt.title, opt.context, opt.vsync);
  display.input().orbit = initial_orbit(cloud);
  gpu::Context& ctx = display.context();
  gpu::Swapchain& sc = display.swapchain();
  GLFWwindow* const window = display.window();
  {
    std::fprintf(stderr, "evflow view: %s, %s, %zu Gaussians\n", ctx.caps().name.c_str(), sc.describe().c_str(),
                 cloud.size());

    GaussianBuffers params(ctx, cloud.size(), cloud.sh_degree, "view");
    params.upload(cloud);
    Rasterizer raster(ctx);
    RenderState raster_state(ctx);
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
    while (!display.should_close()) {
      glfwPollEvents();
      auto now = Clock::now();
      const double dt = std::chrono::duration<double>(now - last_tick).count();
      last_tick = now;
      display.fly(std::min(dt, 0.1));

      if (!display.sync_swapchain()) {  // minimised
        glfwWaitEventsTimeout(0.1);
        continue;
      }
      const uint32_t w = sc.width(), h = sc.height();
      packed.ensure(uint64_t(w) * h * 4);

      const auto t0 = Clock::now();
      const Camera cam = orbit_camera(display.input().orbit, w, h);
      raster.forward(params, cam, settings, raster_state);
      shaderio::PackPC pc{w, h, sc.bgr() ? 1u : 0u};
      cmd.dispatch(
          "view/pack_rgba8",
          {{shaderio::kPackRgba8BindRgb, raster_state.outputs().rgb}, {shaderio::kPackRgba8BindPacked, packed}}, pc,
          cmd.linear_groups(gpu::Commands::div_up(uint64_t(w) * h, shaderio::kViewGroupSize)));
      cmd.submit();
      const bool ok = sc.present(packed);
      render_ms_sum += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (ok) {
        ++shown;
        ++since_title;
        last_valid = true;
        last_w = w;
        last_h = h;
      }
      if (resize_test && !resize_requested && shown >= 2) {
        glfwSetWindowSize(window, int(opt.resize_width), int(opt.resize_height));
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
        display.set_title(title);
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
      std::fprintf(stderr, "evflow view: %d frame(s) presented, wrote %s (%ux%u)\n", shown, opt.screenshot.c_str(),
                   last_w, last_h);
    }
  }
  return report_validation(ctx, "evflow view");
}

}  // namespace evflow::viewer
