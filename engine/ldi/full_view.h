// The LDI network over a whole view, for display (the viewer's LDI panel). Training runs the
// network on crops (ldi_crop); this runs the same weights over the whole sensor with a second
// model of a tile's size, tile by tile. Tiles overlap by the network's reach (one pixel per 3x3
// layer) and each keeps only the part whose inputs all lie inside it, so every pixel equals
// what one forward over the whole view gives (zero padding only at the view's edges). The
// training model is only read (its weights, copied on the device before each evaluation).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "events/gpu_events.h"
#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "ldi/event_bins.h"
#include "ldi/ldi_model.h"

namespace evflow::ldi {

// A tile the model runs on and the part of it that is kept (both in sensor pixels).
struct ViewTile {
  Crop run, keep;
};

// The tiles of a width x height sensor for a tile_w x tile_h model that sees `reach` pixels on
// each side: the kept parts cover the sensor exactly once. Throws when a tile smaller than the
// sensor is not larger than 2 x reach.
std::vector<ViewTile> view_tiles(uint32_t width, uint32_t height, uint32_t tile_w, uint32_t tile_h, uint32_t reach);

// The tiles' side along a sensor axis of `length` pixels for tiles of at most `max_tile`: the
// whole axis when it fits, else the smallest side that covers it with the fewest tiles, so that
// little is computed twice. Throws when max_tile is not larger than 2 x reach.
uint32_t view_tile_side(uint32_t length, uint32_t max_tile, uint32_t reach);

class FullViewFrames {
 public:
  // widths: the network's (as the training model's); tile_w x tile_h: at most the sensor's size;
  // max_frames: the most frame times per evaluation.
  FullViewFrames(gpu::Context& ctx, const GpuEvents& events, const std::vector<uint32_t>& widths, uint32_t tile_w,
                 uint32_t tile_h, uint32_t max_frames);

  uint32_t reach() const { return uint32_t(model_.widths().size() - 1); }
  const std::vector<ViewTile>& tiles() const { return tiles_; }

  // Records frames C_ldi(times[i]) of view `view` over the whole sensor with `source`'s current
  // weights; blurry: the view's blurry image, 3 x H x W, linear.
  void forward(gpu::Commands& cmd, LdiModel& source, size_t view, const std::vector<double>& times,
               const gpu::Buffer& blurry);
  // After forward(): frame i, 3 x H x W linear (H x W: the sensor's size).
  const gpu::Buffer& frame(uint32_t i) const { return frames_.at(i); }

 private:
  void copy_weights(gpu::Commands& cmd, LdiModel& source);

  const GpuEvents& events_;
  LdiModel model_;
  std::vector<ViewTile> tiles_;
  gpu::Buffer tile_blurry_, kept_;
  std::vector<gpu::Buffer> frames_;
};

}  // namespace evflow::ldi
