// The 5 x 7 pixel bitmap font of the plots (plot/raster.h) and the viewer's overlay: upper-case
// letters, digits and common punctuation; lower-case letters are drawn with the upper-case
// glyphs, anything else as a blank cell.
#pragma once

namespace evflow::plot {

inline constexpr int kGlyphW = 5, kGlyphH = 7;

// Whether pixel (x, y) of character c's glyph is lit (x to the right, y down from the top row);
// false outside the 5 x 7 box and for characters without a glyph.
bool glyph_lit(char c, int x, int y);

}  // namespace evflow::plot
