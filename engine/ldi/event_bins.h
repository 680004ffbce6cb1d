// The LDI's event preprocessing P(.) on the GPU (the paper's Sec. 4.5; shaders/ldi/ldi_layout.h).
//
// For a frame time t_i of view w's exposure [t_0, t_2N) (the events' window in GpuEvents), each
// side of t_i gives a 32-channel tensor over a crop of the sensor: kLdiBins = 16 time bins x 2
// polarities, channel 2 * bin + polarity, raw event counts.
//   after  (P(E[t_i, t_2N])): events with t_i <= t < t_2N; bin k holds
//          t_i + k L / 16 <= t < t_i + (k + 1) L / 16, L = t_2N - t_i; polarity as recorded.
//   before (P(E[t_i, t_0])):  events with t_0 <= t < t_i, time running away from t_i; bin k holds
//          t_i - (k + 1) L / 16 <= t < t_i - k L / 16, L = t_i - t_0 (bin 15 from t_0 exactly);
//          polarity flipped (a negative event is channel 2 k + 0).
// Both sides are binned over their own length, so bin k always means "the k-th sixteenth of the
// way from t_i to the end of the exposure": the network sees the same time scale on both sides
// and at every t_i. A side of length 0 is empty.
#pragma once
#include <array>
#include <cstdint>

#include "events/gpu_events.h"
#include "gpu/buffer.h"
#include "gpu/commands.h"
#include "ldi/ldi_layout.h"

namespace evflow::ldi {

enum class Side { Before, After };

// A rectangle of the sensor: pixels x..x+w-1, y..y+h-1.
struct Crop {
  uint32_t x = 0, y = 0, w = 0, h = 0;
  uint64_t pixels() const { return uint64_t(w) * h; }
};

// Throws std::invalid_argument (naming `what`) unless the crop is non-empty and inside a
// width x height sensor.
void check_crop(const Crop& crop, uint32_t width, uint32_t height, const char* what);

// The index ranges of the side's bins in the packed events: bin edges in index order.
std::array<uint32_t, shaderio::kLdiBins + 1> side_bounds(const GpuEvents& events, size_t view, double t_i, Side side);

// Records the side's event tensor (kLdiChannels x crop.h x crop.w floats) into `out`, which it
// overwrites; t_i must lie in the view's window.
void record_side_tensor(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t_i, Side side,
                        const Crop& crop, const gpu::Buffer& out);
// The same for a batch, in two steps: the side's counts (uint) added into image `slot` of a
// batch of such tensors in `out` (zeroed before the first slot), then, once every slot is in,
// record_counts_to_float over the batch's first `values` values.
void record_side_counts(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t_i, Side side,
                        const Crop& crop, const gpu::Buffer& out, uint32_t slot);
void record_counts_to_float(gpu::Commands& cmd, const gpu::Buffer& out, uint64_t values);

// Adds the positive / negative event counts of view w in [t0, t1) over the crop to plane `plane`
// of `counts` (uint, [positive crop][negative crop] per plane): the event loss's counts of a crop.
void record_crop_counts(gpu::Commands& cmd, const GpuEvents& events, size_t view, double t0, double t1,
                        const Crop& crop, const gpu::Buffer& counts, uint32_t plane);

}  // namespace evflow::ldi
