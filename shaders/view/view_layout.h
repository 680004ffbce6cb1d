// Viewer kernels (shaders/view): push constants and buffer records shared by app/viewer and
// shaders/view. The canvas is the swapchain-sized buffer of packed 8-bit pixels (one uint per
// pixel, row-major; bytes R,G,B,A, or B,G,R,A when bgr != 0) that gpu::Swapchain presents.
#ifndef EVF_VIEW_LAYOUT_H
#define EVF_VIEW_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kViewGroupSize, 256u)

// Glyphs of the overlay font: 5 x 7 pixels in a cell of kGlyphCellW x kGlyphCellH (one empty
// column on the right, two empty rows below), each cell pixel drawn as scale x scale.
EVF_CONST(uint, kGlyphW, 5u)
EVF_CONST(uint, kGlyphH, 7u)
EVF_CONST(uint, kGlyphCellW, 6u)
EVF_CONST(uint, kGlyphCellH, 9u)
EVF_CONST(uint, kFontGlyphs, 128u)  // ASCII codes 0..127; the font table holds 2 uints per code:
                                    // word 0: rows 0..3, word 1: rows 4..6, one byte per row,
                                    // bit (4 - x) set when column x of that row is lit.

// view/pack_rgba8: planar linear float RGB [3][H][W] -> the whole canvas.
struct PackPC {
  uint width;
  uint height;
  uint bgr;
};

// view/blit_rgb: planar linear float RGB [3][src_h][src_w] -> the canvas rectangle
// (x, y, w, h), nearest neighbour: the destination pixel dx (0..w-1) shows source column
// ((2 dx + 1) src_w) / (2 w) (integer division; rows the same way). Pixels outside the canvas
// are skipped. Colour handling as in pack_rgba8 (clamp, NaN -> 0, sRGB encode, round).
struct BlitPC {
  uint src_w;
  uint src_h;
  uint canvas_w;
  uint canvas_h;
  uint x;
  uint y;
  uint w;
  uint h;
  uint bgr;
};

// view/fill_rect: the canvas rectangle (x, y, w, h) set to `rgba` (bytes R,G,B,A in memory
// order, swapped to B,G,R,A when bgr != 0).
struct FillPC {
  uint canvas_w;
  uint canvas_h;
  uint x;
  uint y;
  uint w;
  uint h;
  uint rgba;
  uint bgr;
};

// view/text: one record per character; the kernel runs one invocation per cell pixel
// (count x cell_w*scale x cell_h*scale) and writes lit pixels with `fg`, the others with `bg`
// unless draw_bg == 0.
struct Glyph {
  uint x;     // cell's top-left corner on the canvas
  uint y;
  uint code;  // ASCII; codes without a glyph draw as an empty cell
  uint fg;    // rgba, memory byte order R,G,B,A
};
struct TextPC {
  uint count;
  uint scale;
  uint canvas_w;
  uint canvas_h;
  uint bg;
  uint draw_bg;
  uint bgr;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// view/blit_rgb
EVF_BIND(kBlitRgbBindRgb, 0u, Rgb)
EVF_BIND(kBlitRgbBindCanvas, 1u, Canvas)
// view/fill_rect
EVF_BIND(kFillRectBindCanvas, 0u, Canvas)
// view/pack_rgba8
EVF_BIND(kPackRgba8BindRgb, 0u, Rgb)
EVF_BIND(kPackRgba8BindPacked, 1u, Packed)
// view/text
EVF_BIND(kTextBindFont, 0u, Font)
EVF_BIND(kTextBindGlyphs, 1u, Glyphs)
EVF_BIND(kTextBindCanvas, 2u, Canvas)

EVF_NAMESPACE_END
#endif
