// Viewer kernels (shaders/view): push constants and buffer records shared by app/viewer and
// shaders/view. The canvas is the swapchain-sized buffer of packed 8-bit pixels (one uint per
// pixel, row-major; bytes R,G,B,A, or B,G,R,A when bgr != 0) that gpu::Swapchain presents.
#ifndef EVF_VIEW_LAYOUT_H
#define EVF_VIEW_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kViewGroupSize, 256u)

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

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// view/blit_rgb
EVF_BIND(kBlitRgbBindRgb, 0u, Rgb)
EVF_BIND(kBlitRgbBindCanvas, 1u, Canvas)
// view/fill_rect
EVF_BIND(kFillRectBindCanvas, 0u, Canvas)
// view/pack_rgba8
EVF_BIND(kPackRgba8BindRgb, 0u, Rgb)
EVF_BIND(kPackRgba8BindPacked, 1u, Packed)

EVF_NAMESPACE_END
#endif
