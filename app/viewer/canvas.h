// Drawing on the viewer's canvas (the packed RGBA8 buffer the swapchain presents) with the
// kernels of shaders/view: fill a rectangle, blit a planar float RGB image into a rectangle,
// and bitmap-font text. Header-only so the tests can draw with it offscreen.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "view/view_layout.h"
#include "viewer/font.h"
#include "viewer/layout.h"

namespace evflow::viewer {

// rgba word in memory byte order R,G,B,A.
inline constexpr uint32_t rgba(uint32_t r, uint32_t g, uint32_t b, uint32_t a = 255) {
  return (r & 0xFF) | ((g & 0xFF) << 8) | ((b & 0xFF) << 16) | ((a & 0xFF) << 24);
}

class Canvas {
 public:
  Canvas(gpu::Context& ctx, gpu::Commands& cmd)
      : cmd_(cmd),
        packed_(ctx, 16, "view_canvas"),
        font_(ctx, uint64_t(shaderio::kFontGlyphs) * 8, "view_font"),
        glyphs_(ctx, 4096, "view_glyphs") {
    font_.write(font_table());
  }

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

  // Queues a line of text with its top-left corner at (x, y); draw_text() draws all queued text.
  void text(uint32_t x, uint32_t y, const std::string& s, uint32_t color = rgba(255, 255, 255)) {
    for (size_t i = 0; i < s.size(); ++i)
      queued_.push_back(
          {x + uint32_t(i) * shaderio::kGlyphCellW * scale_, y, uint32_t(static_cast<uint8_t>(s[i])), color});
  }
  void set_text_scale(uint32_t s) { scale_ = std::max(1u, s); }
  uint32_t text_scale() const { return scale_; }
  uint32_t line_height() const { return text_height(scale_); }

  // Records the queued text (drawn over everything recorded before), then forgets it. Uploads
  // the glyph records at once: call it once per frame, before the frame's submit.
  void draw_text(bool backdrop = true, uint32_t bg = rgba(0, 0, 0)) {
    if (queued_.empty()) return;
    glyphs_.ensure(queued_.size() * sizeof(shaderio::Glyph));
    glyphs_.write(queued_);
    shaderio::TextPC pc{uint32_t(queued_.size()), scale_, w_, h_, bg, backdrop ? 1u : 0u, bgr_ ? 1u : 0u};
    const uint64_t cell = uint64_t(shaderio::kGlyphCellW) * shaderio::kGlyphCellH * scale_ * scale_;
    cmd_.dispatch(
        "view/text",
        {{shaderio::kTextBindFont, font_}, {shaderio::kTextBindGlyphs, glyphs_}, {shaderio::kTextBindCanvas, packed_}},
        pc, groups(queued_.size() * cell));
    queued_.clear();
  }

 private:
  gpu::Groups groups(uint64_t n) const {
    return cmd_.linear_groups(gpu::Commands::div_up(n, shaderio::kViewGroupSize));
  }
  gpu::Commands& cmd_;
  gpu::Buffer packed_, font_, glyphs_;
  std::vector<shaderio::Glyph> queued_;
  uint32_t w_ = 0, h_ = 0, scale_ = 1;
  bool bgr_ = false;
};

}  // namespace evflow::viewer
