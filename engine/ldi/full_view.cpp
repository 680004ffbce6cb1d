#include "ldi/full_view.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "ldi/crop.h"

namespace evflow::ldi {

namespace {

// Along one axis: the tile's start and the kept range [from, to).
struct Span {
  uint32_t run, from, to;
};

// A tile starting at `run` keeps [run + reach, run + tile - reach), widened to the sensor's
// edge where it touches one; the next tile starts `reach` before the kept range ends.
std::vector<Span> spans(uint32_t length, uint32_t tile, uint32_t reach) {
  if (tile >= length) return {{0, 0, length}};
  if (tile <= 2 * reach)
    throw std::invalid_argument("LDI view tiles: a tile of " + std::to_string(tile) + " pixels keeps nothing of a " +
                                "network that reaches " + std::to_string(reach) + " pixels each way");
  std::vector<Span> out;
  for (uint32_t from = 0; from < length;) {
    const uint32_t run = from < reach ? 0 : std::min(from - reach, length - tile);
    const uint32_t to = run + tile == length ? length : run + tile - reach;
    out.push_back({run, from, to});
    from = to;
  }
  return out;
}

}  // namespace

std::vector<ViewTile> view_tiles(uint32_t width, uint32_t height, uint32_t tile_w, uint32_t tile_h, uint32_t reach) {
  if (width == 0 || height == 0 || tile_w == 0 || tile_h == 0)
    throw std::invalid_argument("LDI view tiles: an empty sensor or tile");
  std::vector<ViewTile> tiles;
  const uint32_t tw = std::min(tile_w, width), th = std::min(tile_h, height);
  for (const Span& y : spans(height, th, reach))
    for (const Span& x : spans(width, tw, reach))
      tiles.push_back({{x.run, y.run, tw, th}, {x.from, y.from, x.to - x.from, y.to - y.from}});
  return tiles;
}

// n tiles keep n (side - 2 reach) + 2 reach pixels (the first and last also their outer reach).
uint32_t view_tile_side(uint32_t length, uint32_t max_tile, uint32_t reach) {
  if (length <= max_tile) return length;
  if (max_tile <= 2 * reach)
    throw std::invalid_argument("LDI view tiles: tiles of at most " + std::to_string(max_tile) +
                                " pixels keep nothing of a network that reaches " + std::to_string(reach) +
                                " pixels each way");
  const uint32_t inner = length - 2 * reach, n = (inner + (max_tile - 2 * reach) - 1) / (max_tile - 2 * reach);
  return (inner + n - 1) / n + 2 * reach;
}

FullViewFrames::FullViewFrames(gpu::Context& ctx, const GpuEvents& events, const std::vector<uint32_t>& widths,
                               uint32_t tile_w, uint32_t tile_h, uint32_t max_frames)
    : events_(events),
      model_(ctx, events, widths, tile_w, tile_h, max_frames),
      tiles_(view_tiles(events.width(), events.height(), tile_w, tile_h, uint32_t(widths.size() - 1))),
      tile_blurry_(ctx, 3ull * tile_w * tile_h * 4, "ldi_view_tile_blurry"),
      kept_(ctx, 3ull * tile_w * tile_h * 4, "ldi_view_tile_kept") {
  for (uint32_t i = 0; i < max_frames; ++i)
    frames_.emplace_back(ctx, 3ull * events.width() * events.height() * 4, "ldi_view_frame");
}

// The training model's weights into the tile model, on the device (recorded: the copy sees
// whatever the commands before it wrote).
void FullViewFrames::copy_weights(gpu::Commands& cmd, LdiModel& source) {
  if (source.widths() != model_.widths())
    throw std::invalid_argument("LDI view frames: the source network's widths differ from the tile model's");
  for (size_t l = 0; l < model_.network().layers(); ++l) {
    const nn::Conv2d& from = source.network().layer(l);
    const nn::Conv2d& to = model_.network().layer(l);
    cmd.copy(from.weight(), to.weight(), from.weight_count() * 4);
    cmd.copy(from.bias(), to.bias(), uint64_t(from.spec().out_c) * 4);
  }
}

void FullViewFrames::forward(gpu::Commands& cmd, LdiModel& source, size_t view, const std::vector<double>& times,
                             const gpu::Buffer& blurry) {
  const uint32_t W = events_.width(), H = events_.height();
  if (times.empty() || times.size() > frames_.size())
    throw std::invalid_argument("LDI view frames: " + std::to_string(times.size()) + " frame times for at most " +
                                std::to_string(frames_.size()));
  if (blurry.size() < 3ull * W * H * 4) throw std::invalid_argument("LDI view frames: the blurry image is too small");
  copy_weights(cmd, source);
  for (uint32_t i = 0; i < times.size(); ++i) cmd.fill(frames_[i], 0u);
  for (const ViewTile& t : tiles_) {
    record_crop(cmd, blurry, W, H, 3, t.run, tile_blurry_);
    model_.forward(cmd, view, times, t.run, tile_blurry_);
    const Crop inner{t.keep.x - t.run.x, t.keep.y - t.run.y, t.keep.w, t.keep.h};
    for (uint32_t i = 0; i < times.size(); ++i) {
      record_crop(cmd, model_.frame(i), t.run.w, t.run.h, 3, inner, kept_);
      record_uncrop_add(cmd, kept_, W, H, 3, t.keep, frames_[i]);
    }
  }
}

}  // namespace evflow::ldi
