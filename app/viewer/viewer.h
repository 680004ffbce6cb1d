// `evflow view`: a GLFW window showing splats through the Vulkan swapchain (docs/viewer.md).
// The frame is rendered by Rasterizer::forward, packed to sRGB-encoded RGBA8 by the kernel
// "view/pack_rgba8" and copied into the swapchain image by gpu::Swapchain.
#pragma once
#include <cstdint>
#include <string>

#include "gpu/context.h"
#include "splat/gaussians.h"

namespace evflow::viewer {

struct ViewerOptions {
  uint32_t width = 800, height = 600;  // initial window size (screen coordinates)
  int frames = 0;                      // > 0: exit after this many presented frames
  std::string screenshot;              // PNG of the last presented frame, written at exit
  double fps_cap = 30.0;               // <= 0: uncapped
  bool vsync = false;
  // Testing the swapchain rebuild: after 2 presented frames the window is resized to this
  // size, and the run ends only once `frames` frames in all, the last of that size, were shown.
  uint32_t resize_width = 0, resize_height = 0;
  std::string title = "evflow view";
  gpu::ContextOptions context;  // presentation is switched on by the viewer
};

// Opens the window and runs until it is closed (or `frames` were shown). Returns the process
// exit status: 0, or 3 when the validation layer reported anything (the messages are printed).
// Throws std::runtime_error when no window can be opened (no display, no Vulkan surface).
int run_viewer(const GaussianCloud& cloud, const ViewerOptions& options);

}  // namespace evflow::viewer
