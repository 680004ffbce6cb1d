// Where things go in the training viewer's window, as pure functions (header-only: the tests
// use them to find a panel in a screenshot and to resample images exactly as the viewer does).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

namespace evflow::viewer {

struct Rect {
  uint32_t x = 0, y = 0, w = 0, h = 0;
  bool empty() const { return w == 0 || h == 0; }
};

// Nearest-neighbour resampling used by the kernel "view/blit_rgb": destination index d of a
// span of `dst_len` pixels shows source index ((2 d + 1) src_len) / (2 dst_len).
inline uint32_t nearest_source(uint32_t d, uint32_t dst_len, uint32_t src_len) {
  return std::min<uint32_t>(uint32_t((uint64_t(2 * d + 1) * src_len) / (uint64_t(2) * dst_len)), src_len - 1);
}

// The largest rectangle of aspect src_w : src_h inside `box`, centred (integer pixels).
inline Rect fit_aspect(const Rect& box, uint32_t src_w, uint32_t src_h) {
  if (box.empty() || src_w == 0 || src_h == 0) return {box.x, box.y, 0, 0};
  uint32_t w = box.w, h = uint32_t(uint64_t(box.w) * src_h / src_w);
  if (h > box.h) {
    h = box.h;
    w = uint32_t(uint64_t(box.h) * src_w / src_h);
  }
  w = std::max<uint32_t>(w, 1);
  h = std::max<uint32_t>(h, 1);
  return {box.x + (box.w - w) / 2, box.y + (box.h - h) / 2, w, h};
}

// `count` tiles of aspect src_w : src_h in `box`: the grid (columns x rows) that gives the
// largest tiles; each tile centred in its grid cell. Row-major order. group > 1 (dividing
// count): the columns are a multiple of it, so that each group of tiles shares a row.
inline std::vector<Rect> tile_grid(const Rect& box, uint32_t count, uint32_t src_w, uint32_t src_h, uint32_t gap = 2,
                                   uint32_t group = 1) {
  std::vector<Rect> best;
  uint64_t best_area = 0;
  const uint32_t g = group > 1 && count % group == 0 ? group : 1;
  for (uint32_t cols = g; cols <= count; cols += g) {
    const uint32_t rows = (count + cols - 1) / cols;
    if (box.w < cols * (gap + 1) || box.h < rows * (gap + 1)) break;
    const uint32_t cw = (box.w - (cols - 1) * gap) / cols, ch = (box.h - (rows - 1) * gap) / rows;
    std::vector<Rect> tiles;
    for (uint32_t i = 0; i < count; ++i) {
      const Rect cell{box.x + (i % cols) * (cw + gap), box.y + (i / cols) * (ch + gap), cw, ch};
      tiles.push_back(fit_aspect(cell, src_w, src_h));
    }
    const uint64_t area = uint64_t(tiles[0].w) * tiles[0].h;
    if (area > best_area) {
      best_area = area;
      best = std::move(tiles);
    }
  }
  return best;
}

// The training viewer's layout: the free-camera view on the left (the whole window when no
// side panel is shown), the side panels in a grid on the right half (one column for up to two
// panels, else two), each cell a label strip of `label_h` pixels above its content box.
struct TrainLayout {
  Rect main;
  std::vector<Rect> labels, boxes;  // per visible side panel, in list order
};

inline TrainLayout train_layout(uint32_t canvas_w, uint32_t canvas_h, uint32_t side_panels, uint32_t label_h) {
  TrainLayout l;
  if (side_panels == 0) {
    l.main = {0, 0, canvas_w, canvas_h};
    return l;
  }
  const uint32_t main_w = canvas_w / 2;
  l.main = {0, 0, main_w, canvas_h};
  const uint32_t cols = side_panels <= 2 ? 1 : 2, rows = (side_panels + cols - 1) / cols;
  const uint32_t side_w = canvas_w - main_w, cell_w = side_w / cols, cell_h = canvas_h / rows;
  for (uint32_t i = 0; i < side_panels; ++i) {
    const uint32_t x = main_w + (i % cols) * cell_w, y = (i / cols) * cell_h;
    const uint32_t lh = std::min(label_h, cell_h);
    l.labels.push_back({x, y, cell_w, lh});
    // One pixel of margin on each side of the content box.
    const uint32_t bw = cell_w > 2 ? cell_w - 2 : 0, bh = cell_h > lh + 2 ? cell_h - lh - 2 : 0;
    l.boxes.push_back({x + 1, y + lh + 1, bw, bh});
  }
  return l;
}

}  // namespace evflow::viewer
