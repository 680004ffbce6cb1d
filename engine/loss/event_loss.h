// The event loss L_ev^gs (paper Eq. 5; docs/losses.md). For the 2N+1 virtual frames t_0..t_2N of
// an exposure and each i = 0..2N-1, with t_s drawn uniformly from {t_0, ..., t_i}:
//
//   l_i = || E(t_s, t_{i+1}) / ||E|| - D(t_s, t_{i+1}) / ||D|| ||^2,   L = (1 / 2N) sum_i l_i,
//
//   E(t_s, t_j) = Θ+ · #positive events - Θ- · #negative events in [t_s, t_j), per pixel,
//   D(t_s, t_j) = log(eps + Y_j) - log(eps + Y_s),  Y = luminance of the linear render,
//
// norms over the whole image. D is "later minus earlier": the direction in which an event's
// polarity points (the simulator fires +1 when log Y grows; tests/test_event_loss.cpp checks the
// sign on simulated events). Normalising both sides removes the unknown threshold scale. A norm
// below sqrt(H·W)·norm_floor_rms is held at that floor, so nearly static frame pairs (the
// trajectories start at rest) don't turn into huge gradients.
//
// GPU work per record: the events of each of the 2N frame intervals are counted into their own
// plane (integer atomics, exact), and each pair sums its planes; every reduction is in a fixed
// order, so the value and the gradients are reproducible on a device. Per pixel (and H·W a
// multiple of 4) one pass takes every pair at once, reading each plane and frame once, and one
// backward pass adds each frame's gradient once (event_pairs kernels); otherwise each pair has
// its own passes. A view's planes are kept
// for its next records (its frame times and events rarely change), up to count_cache_bytes in all.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "events/interval_events.h"
#include "loss/event_pooling.h"
#include "loss/loss_term.h"

namespace evflow {
namespace shaderio {
struct EventPairPC;
struct EventPairsPC;
}  // namespace shaderio

struct EventLossOptions {
  float theta_pos = 0.2f, theta_neg = 0.2f;  // log units per positive / negative event
  float eps = 1e-3f;                         // L = log(eps + Y), the event model's eps
  float norm_floor_rms = 1e-3f;              // per-pixel RMS below which a norm is floored
  uint32_t pool = 1;                         // side of the pooling cells (loss/event_pooling.h)
  // The most bytes of count planes kept across records, one set per view; past it the views
  // share one set, counted again whenever the view changes.
  uint64_t count_cache_bytes = 256ull << 20;
};

class EventLoss : public ExposureLossTerm {
 public:
  // `events` holds one window per training view (ExposureFrames::view indexes it); it must
  // outlive the term.
  EventLoss(gpu::Context& ctx, const IntervalEvents& events, float weight, EventLossOptions options = {});
  using ExposureLossTerm::record;
  void record(gpu::Commands& cmd, const ExposureFrames& frames, float weight) override;
  // Where every pair is taken in one pass (takes_pairs_at_once); with render_grad, where the device
  // also binds every render in that pass (2 + 3 F texel buffers).
  bool folds(const ExposureFrames& frames) const override;
  // The value alone, for the same frames and seed (frames.grad is not read and may be empty):
  // what record() writes into the value slot, at a fraction of the cost (score_reversed_next's
  // way with pooled cells).
  void record_value(gpu::Commands& cmd, const ExposureFrames& frames);
  // At the next record() only: also the value record_value() would write for the same frames in
  // the time-reversed order, into out[index] (floats). Where every pair is taken in one pass
  // (takes_pairs_at_once) it comes from the forward order's own pass; otherwise from a record_value()
  // of its own first. The trainer's direction check uses it.
  void score_reversed_next(const gpu::Buffer& out, uint32_t index);

  // The pairs (s, j = i + 1) for F frames and a seed: s uniform in {0..i} (deterministic).
  static std::vector<std::pair<uint32_t, uint32_t>> sample_pairs(uint32_t frames, uint64_t seed);
  const std::vector<std::pair<uint32_t, uint32_t>>& last_pairs() const { return pairs_; }
  const EventLossOptions& options() const { return options_; }
  // Whether a record of these frames takes every pair in one pass (loss/event_pairs_f<F> ...): per
  // pixel, H*W a multiple of 4, up to kEventPairsMaxFrames frames, on a device that binds them
  // all in one kernel; else a pass per pair.
  bool takes_pairs_at_once(const ExposureFrames& frames) const;
  // Per-pixel counts of the last record, 2 * H * W values per interval plane: uints, or floats
  // when the events' float_planes() (for viewers and tests).
  const gpu::Buffer& counts() const { return *last_counts_; }
  // How many records counted their events (a record for a view whose planes are kept, with the
  // same frame times and events, reuses them).
  uint64_t count_passes() const { return count_passes_; }

 private:
  // One set of interval planes and what it holds: the frame times and events' generation of its
  // last counting pass (empty times: nothing). It assumes each record's commands are submitted
  // (a discarded batch would leave it stale).
  struct CountPlanes {
    gpu::Buffer planes;
    uint32_t view = 0;
    std::vector<double> times;
    uint64_t generation = 0;
  };
  // Checks the frames, counts the view's events unless its planes hold them, draws the pairs.
  const gpu::Buffer& counted_planes(gpu::Commands& cmd, const ExposureFrames& frames, bool gradients);
  // Any pooling and size: per pair, a pass over the cells (loss/event_pair ...).
  void record_pairs(gpu::Commands& cmd, const ExposureFrames& frames, float weight, bool gradients);
  shaderio::EventPairPC pair_constants(const ExposureFrames& frames, float weight, uint32_t pair) const;
  void record_fused(gpu::Commands& cmd, const ExposureFrames& frames, float weight, bool gradients);
  void check_folded(const ExposureFrames& frames) const;
  shaderio::EventPairsPC pairs_constants(const ExposureFrames& frames, float weight, uint32_t groups) const;
  float norm_floor2(const ExposureFrames& frames) const;
  CountPlanes& planes_for(uint32_t view, uint64_t bytes);

  const IntervalEvents& events_;
  EventLossOptions options_;
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
  gpu::Buffer scratch_, partials_, sums_;
  const gpu::Buffer* reversed_out_ = nullptr;  // score_reversed_next's request, for one record
  uint32_t reversed_index_ = 0;
  std::vector<CountPlanes> kept_;  // per view, when all fit options_.count_cache_bytes
  CountPlanes shared_;             // every view past them
  const gpu::Buffer* last_counts_ = &shared_.planes;
  uint64_t count_passes_ = 0;
};

}  // namespace evflow
