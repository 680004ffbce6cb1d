// Drawing on the viewer's canvas (the packed RGBA8 buffer the swapchain presents) with the
// kernels of shaders/view: fill a rectangle, blit a planar float RGB image into a rectangle.
// Text is the UI's (Dear ImGui, drawn over the presented frame). Header-only so the tests can
// draw with it offscreen.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "view/view_layout.h"
#include "viewer/layout.h"

namespace evflow::viewer {

// rgba word in memory byte order R,G,B,A.
inline constexpr uint32_t rgba(uint32_t r, uint32_t g, uint32_t b, uint32_t a = 255) {
  return (r & 0xFF) | ((g & 0xFF) << 8) | ((b & 0xFF) << 16) | ((a & 0xFF) << 24);
}

class Canvas {
 public:
  Canvas(gpu::Context& ctx, gpu::Commands& cmd) : cmd_(cmd), packed_(ctx, 16, "view_canvas") {}

  // Sets the size (contents undefined afterwards) and the byte order of the swapchain.
  void resize(uint32_t w, uint32_t h, bool bgr) {
    w_ = w;
    h_ = h;
    bgr_ = bgr;
    packed_.ensure(uint64_t(std::max(w, 1u)) * std::max(h, 1u) * 4);
  }
  uint32_t width() const { return w_; }
  uint32_t height() const { return h_; }
  bool bgr() const { return bgr_; }
  const gpu::Buffer& packed() const { return packed_; }

  void fill(const Rect& r, uint32_t color) {
    if (r.empty()) return;
    shaderio::FillPC pc{w_, h_, r.x, r.y, r.w, r.h, color, bgr_ ? 1u : 0u};
    cmd_.dispatch("view/fill_rect", {{shaderio::kFillRectBindCanvas, packed_}}, pc, groups(uint64_t(r.w) * r.h));
  }

  // `rgb`: planar linear float [3][src_h][src_w].
  void blit(const gpu::Buffer& rgb, uint32_t src_w, uint32_t src_h, const Rect& r) {
    if (r.empty() || src_w == 0 || src_h == 0) return;
    shaderio::BlitPC pc{src_w, src_h, w_, h_, r.x, r.y, r.w, r.h, bgr_ ? 1u : 0u};
    cmd_.dispatch("view/blit_rgb", {{shaderio::kBlitRgbBindRgb, rgb}, {shaderio::kBlitRgbBindCanvas, packed_}}, pc,
                  groups(uint64_t(r.w) * r.h));
  }

 private:
  gpu::Groups groups(uint64_t n) const {
    return cmd_.linear_groups(gpu::Commands::div_up(n, shaderio::kViewGroupSize));
  }
  gpu::Commands& cmd_;
  gpu::Buffer packed_;
  uint32_t w_ = 0, h_ = 0;
  bool bgr_ = false;
};

}  // namespace evflow::viewer
