#version 450
// Bitmap-font text on the packed canvas: one invocation per pixel of each character cell
// (Glyph records and the font table layout in view_layout.h). Lit glyph pixels get the glyph's
// colour; the rest of the cell gets pc.bg when pc.draw_bg != 0 (a backdrop that keeps the text
// readable over any image).
#extension GL_GOOGLE_include_directive : require
#include "view/view_layout.h"
#include "view/srgb8.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kViewGroupSize) in;
layout(std430, binding = kTextBindFont) readonly buffer Font { uint font[]; };
layout(std430, binding = kTextBindGlyphs) readonly buffer Glyphs { Glyph glyphs[]; };
layout(std430, binding = kTextBindCanvas) buffer Canvas { uint canvas[]; };
layout(push_constant) uniform PCBlock { TextPC pc; };

void main() {
  uint i = evf_linear_invocation(kViewGroupSize);
  uint cw = kGlyphCellW * pc.scale, ch = kGlyphCellH * pc.scale, cell = cw * ch;
  if (i >= pc.count * cell) return;
  Glyph g = glyphs[i / cell];
  uint local = i % cell;
  uint px = local % cw, py = local / cw;
  uint X = g.x + px, Y = g.y + py;
  if (X >= pc.canvas_w || Y >= pc.canvas_h) return;
  uint gx = px / pc.scale, gy = py / pc.scale;
  bool lit = false;
  if (g.code < kFontGlyphs && gx < kGlyphW && gy < kGlyphH) {
    uint word = font[g.code * 2u + (gy < 4u ? 0u : 1u)];
    uint row = (word >> (8u * (gy % 4u))) & 0xFFu;
    lit = ((row >> (4u - gx)) & 1u) != 0u;
  }
  if (lit) canvas[Y * pc.canvas_w + X] = evf_canvas_rgba(g.fg, pc.bgr);
  else if (pc.draw_bg != 0u) canvas[Y * pc.canvas_w + X] = evf_canvas_rgba(pc.bg, pc.bgr);
}
