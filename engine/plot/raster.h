// A small RGB raster for plots: pixels, straight lines, filled rectangles and text in the 5 x 7
// bitmap font (plot/bitmap_font.h), saved as an 8-bit PNG (io/image.h).
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace evflow::plot {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

class Raster {
 public:
  Raster(int width, int height, Rgb background);
  int width() const { return width_; }
  int height() const { return height_; }
  Rgb at(int x, int y) const;  // (0, 0) top left; throws outside the raster
  // Drawing clips to the raster: pixels outside it are left out.
  void set(int x, int y, Rgb c);
  void fill_rect(int x0, int y0, int x1, int y1, Rgb c);  // corners inclusive, in any order
  void line(int x0, int y0, int x1, int y1, Rgb c);       // both end points drawn, 8-connected
  // Text with its top-left corner at (x, y): cells of kCellW x kCellH pixels per character.
  void text(int x, int y, const std::string& s, Rgb c);
  static constexpr int kCellW = 6, kCellH = 9;
  static int text_width(const std::string& s) { return int(s.size()) * kCellW; }
  const std::vector<uint8_t>& rgb8() const { return pixels_; }  // interleaved RGB, rows top to bottom
  void write_png(const std::filesystem::path& path) const;      // atomic (io/atomic_file.h)

 private:
  int width_, height_;
  std::vector<uint8_t> pixels_;
};

}  // namespace evflow::plot
