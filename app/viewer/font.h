// The overlay's bitmap font: the 5 x 7 pixel glyphs of plot/bitmap_font.h drawn by the kernel
// "view/text" (layout of the table in shaders/view/view_layout.h).
// Header-only: the tests rasterise text on the host with text_pixel_lit() and compare.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "plot/bitmap_font.h"
#include "view/view_layout.h"

namespace evflow::viewer {

// The table uploaded to the "view/text" kernel: 2 uints per ASCII code (view_layout.h).
inline std::vector<uint32_t> font_table() {
  static_assert(shaderio::kGlyphW == plot::kGlyphW && shaderio::kGlyphH == plot::kGlyphH);
  std::vector<uint32_t> t(size_t(shaderio::kFontGlyphs) * 2, 0u);
  for (uint32_t code = 0; code < shaderio::kFontGlyphs; ++code)
    for (uint32_t y = 0; y < shaderio::kGlyphH; ++y) {
      uint32_t row = 0;
      for (uint32_t x = 0; x < shaderio::kGlyphW; ++x)
        if (plot::glyph_lit(char(code), int(x), int(y))) row |= 1u << (4 - x);
      t[size_t(code) * 2 + (y < 4 ? 0 : 1)] |= row << (8 * (y % 4));
    }
  return t;
}

// Whether glyph pixel (gx, gy) of `code` is lit (the host reference of the kernel's test).
inline bool glyph_pixel_lit(const std::vector<uint32_t>& table, uint32_t code, uint32_t gx, uint32_t gy) {
  if (code >= shaderio::kFontGlyphs || gx >= shaderio::kGlyphW || gy >= shaderio::kGlyphH) return false;
  const uint32_t word = table[size_t(code) * 2 + (gy < 4 ? 0 : 1)];
  return ((word >> (8 * (gy % 4))) >> (4 - gx) & 1u) != 0;
}

// Width and height in pixels of one line of `n` characters at `scale`.
inline uint32_t text_width(size_t n, uint32_t scale) { return uint32_t(n) * shaderio::kGlyphCellW * scale; }
inline uint32_t text_height(uint32_t scale) { return shaderio::kGlyphCellH * scale; }

}  // namespace evflow::viewer
