#include "loss/event_loss.h"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

#include "loss/event_sums.h"
#include "loss/loss_layout.h"

namespace evflow {

EventLoss::EventLoss(gpu::Context& ctx, const IntervalEvents& events, float weight, EventLossOptions options)
    : ExposureLossTerm(ctx, "events", weight, 1),
      events_(events),
      options_(options),
      scratch_(ctx, 16, "event_scratch"),
      partials_(ctx, 16, "event_partials"),
      sums_(ctx, 16, "event_sums") {
  if (!(options.theta_pos > 0 && options.theta_neg > 0))
    throw std::invalid_argument("event loss: thresholds must be > 0");
  if (!(options.eps > 0)) throw std::invalid_argument("event loss: eps must be > 0");
  if (!(options.norm_floor_rms > 0)) throw std::invalid_argument("event loss: norm_floor_rms must be > 0");
  check_event_pool(options.pool, "event loss");
  shared_.planes = gpu::Buffer(ctx, 16, "event_counts");
}

// The planes a view's counts live in: its own when every view's fit count_cache_bytes, else the
// shared set.
EventLoss::CountPlanes& EventLoss::planes_for(uint32_t view, uint64_t bytes) {
  const uint64_t views = events_.window_count();
  if (kept_.empty() && views * bytes <= options_.count_cache_bytes) {
    kept_.resize(views);
    for (uint32_t v = 0; v < views; ++v) {
      kept_[v].view = v;
      kept_[v].planes = gpu::Buffer(ctx_, bytes, "event_counts_view" + std::to_string(v));
    }
  }
  CountPlanes& p = view < kept_.size() && kept_[view].planes.size() >= bytes ? kept_[view] : shared_;
  if (&p == &shared_ && p.view != view) p.times.clear();
  return p;
}

std::vector<std::pair<uint32_t, uint32_t>> EventLoss::sample_pairs(uint32_t frames, uint64_t seed) {
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 0xE7037ED1A0B428DBull);
  for (uint32_t i = 0; i + 1 < frames; ++i) pairs.emplace_back(uint32_t(rng() % (i + 1)), i + 1);
  return pairs;
}

void EventLoss::score_reversed_next(const gpu::Buffer& out, uint32_t index) {
  reversed_out_ = &out;
  reversed_index_ = index;
}

bool EventLoss::takes_pairs_at_once(const ExposureFrames& f) const {
  const uint32_t F = uint32_t(f.u.size());
  // The backward binds F gradient images, the counts, the sums, every frame and a view of each gradient.
  return options_.pool == 1 && (uint64_t(f.width) * f.height) % 4 == 0 && F >= 2 &&
         F <= shaderio::kEventPairsMaxFrames && ctx_.caps().fits_bindings(F, 2 + 2 * F);
}

// The _decode backward binds what the plain one does (it takes decode' from the linear frames).
bool EventLoss::folds(const ExposureFrames& f) const { return takes_pairs_at_once(f); }

void EventLoss::record(gpu::Commands& cmd, const ExposureFrames& f, float weight) {
  if ((!f.grad_in.empty() || !f.render_grad.empty()) && !folds(f))
    throw std::invalid_argument(
        "event loss: these frames take a pass per pair, which adds into grad only (no grad_in, "
        "no render gradients)");
  if (takes_pairs_at_once(f))
    record_fused(cmd, f, weight, true);
  else {
    if (reversed_out_) {  // its own value record, before the forward order's overwrites the slot
      ExposureFrames r = f;
      std::reverse(r.rgb.begin(), r.rgb.end());
      r.grad.clear();
      record_pairs(cmd, r, 0.0f, false);
      cmd.copy(value_buffer(), *reversed_out_, 4, uint64_t(value_offset()) * 4, uint64_t(reversed_index_) * 4);
    }
    record_pairs(cmd, f, weight, true);
  }
  reversed_out_ = nullptr;
}

void EventLoss::record_value(gpu::Commands& cmd, const ExposureFrames& f) {
  const gpu::Buffer* reversed = reversed_out_;
  reversed_out_ = nullptr;  // the value alone; a pending request stays for the next record()
  if (takes_pairs_at_once(f))
    record_fused(cmd, f, 0.0f, false);
  else
    record_pairs(cmd, f, 0.0f, false);
  reversed_out_ = reversed;
}

const gpu::Buffer& EventLoss::counted_planes(gpu::Commands& cmd, const ExposureFrames& f, bool gradients) {
  const uint32_t F = uint32_t(f.u.size());
  if (F < 2) throw std::invalid_argument("event loss: needs at least 2 virtual frames, got " + std::to_string(F));
  if (f.rgb.size() != F || (gradients && f.grad.size() != F))
    throw std::invalid_argument("event loss: " + std::to_string(F) + " frame times but " +
                                std::to_string(f.rgb.size()) + " renders and " + std::to_string(f.grad.size()) +
                                " gradient images");
  if (f.width != events_.width() || f.height != events_.height())
    throw std::invalid_argument("event loss: frames are " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                                " but the events' sensor is " + std::to_string(events_.width()) + "x" +
                                std::to_string(events_.height()));
  if (f.view >= events_.window_count())
    throw std::invalid_argument("event loss: view " + std::to_string(f.view) + " has no event window");
  const uint64_t hw = uint64_t(f.width) * f.height;
  for (uint32_t i = 0; i < F; ++i)
    if (f.rgb[i]->size() < hw * 12 || (gradients && f.grad[i]->size() < hw * 12))
      throw std::invalid_argument("event loss: frame " + std::to_string(i) +
                                  " buffers hold less than 3 x H x W floats");
  const uint32_t intervals = F - 1;
  const uint64_t count_bytes = uint64_t(intervals) * 2 * hw * 4;
  ctx_.check_binding_size(count_bytes, "event loss counts");

  // Every interval's events once, into its own plane (unless the view's planes hold them already).
  std::vector<double> times(F);
  for (uint32_t i = 0; i < F; ++i) times[i] = f.time_at(i);
  CountPlanes& counted = planes_for(f.view, count_bytes);
  counted.planes.ensure(count_bytes);
  if (times != counted.times || events_.generation() != counted.generation) {
    cmd.fill(counted.planes, 0u);
    for (uint32_t k = 0; k < intervals; ++k) events_.accumulate(cmd, f.view, times[k], times[k + 1], counted.planes, k);
    counted.view = f.view;
    counted.times = times;
    counted.generation = events_.generation();
    ++count_passes_;
  }
  last_counts_ = &counted.planes;
  pairs_ = sample_pairs(F, f.seed);
  return counted.planes;
}

shaderio::EventPairPC EventLoss::pair_constants(const ExposureFrames& f, float weight, uint32_t q) const {
  const auto [s, j] = pairs_[q];
  shaderio::EventPairPC pc{};
  pc.width = f.width;
  pc.height = f.height;
  pc.plane_first = s;
  pc.plane_last = j - 1;
  pc.theta_pos = options_.theta_pos;
  pc.theta_neg = options_.theta_neg;
  pc.eps = options_.eps;
  pc.norm_floor2 = norm_floor2(f);
  pc.grad_scale = weight / float(pairs_.size());
  pc.value_scale = 1.0f / float(pairs_.size());
  pc.value_accumulate = q > 0 ? 1u : 0u;
  pc.value_index = value_offset();
  pc.pair = q;
  pc.counts_float = events_.float_planes() ? 1u : 0u;
  pc.pool = options_.pool;
  return pc;
}

float EventLoss::norm_floor2(const ExposureFrames& f) const {
  return float(double(options_.norm_floor_rms) * options_.norm_floor_rms * double(uint64_t(f.width) * f.height));
}

void EventLoss::record_pairs(gpu::Commands& cmd, const ExposureFrames& f, float weight, bool gradients) {
  const gpu::Buffer& counts = counted_planes(cmd, f, gradients);
  const uint64_t hw = uint64_t(f.width) * f.height;
  const uint32_t groups = gpu::Commands::div_up(hw, shaderio::kLossGroupSize);
  const uint64_t cells = event_pool_cells(f.width, f.height, options_.pool);
  const uint32_t cell_groups = gpu::Commands::div_up(cells, shaderio::kLossGroupSize);
  scratch_.ensure(2 * cells * 4);
  partials_.ensure(uint64_t(cell_groups) * 16);
  sums_.ensure(uint64_t(pairs_.size()) * 16);
  const gpu::Groups g = cmd.linear_groups(groups), gc = cmd.linear_groups(cell_groups);
  for (uint32_t q = 0; q < pairs_.size(); ++q) {
    const auto [s, j] = pairs_[q];
    const shaderio::EventPairPC pc = pair_constants(f, weight, q);
    cmd.dispatch("loss/event_pair",
                 {{shaderio::kEventPairBindCounts, counts},
                  {shaderio::kEventPairBindFrameS, *f.rgb[s]},
                  {shaderio::kEventPairBindFrameJ, *f.rgb[j]},
                  {shaderio::kEventPairBindScratch, scratch_},
                  {shaderio::kEventPairBindPartials, partials_}},
                 pc, gc);
    record_event_sums(cmd, partials_, sums_, cell_groups, 4 * q);
    if (gradients)
      cmd.dispatch("loss/event_pair_bwd",
                   {{shaderio::kEventPairBwdBindFrameS, *f.rgb[s]},
                    {shaderio::kEventPairBwdBindFrameJ, *f.rgb[j]},
                    {shaderio::kEventPairBwdBindScratch, scratch_},
                    {shaderio::kEventPairBwdBindSums, sums_},
                    {shaderio::kEventPairBwdBindGradS, *f.grad[s]},
                    {shaderio::kEventPairBwdBindGradJ, *f.grad[j]},
                    {shaderio::kEventPairBwdBindValues, value_buffer()}},
                   pc, g);
    else
      cmd.dispatch("loss/event_pair_value",
                   {{shaderio::kEventPairValueBindSums, sums_}, {shaderio::kEventPairValueBindValues, value_buffer()}},
                   pc, gpu::Groups{1, 1, 1});
  }
}

shaderio::EventPairsPC EventLoss::pairs_constants(const ExposureFrames& f, float weight, uint32_t groups) const {
  const uint32_t P = uint32_t(pairs_.size());
  shaderio::EventPairsPC pc{};
  pc.width = f.width;
  pc.height = f.height;
  pc.pairs = P;
  for (uint32_t q = 0; q < P; ++q) pc.s_packed |= pairs_[q].first << (4 * q);
  pc.theta_pos = options_.theta_pos;
  pc.theta_neg = options_.theta_neg;
  pc.eps = options_.eps;
  pc.norm_floor2 = norm_floor2(f);
  pc.grad_scale = weight / float(P);
  pc.value_scale = 1.0f / float(P);
  pc.value_index = value_offset();
  pc.reversed = reversed_out_ ? 1u : 0u;
  pc.reversed_index = reversed_index_;
  pc.counts_float = events_.float_planes() ? 1u : 0u;
  pc.groups = groups;
  return pc;
}

void EventLoss::record_fused(gpu::Commands& cmd, const ExposureFrames& f, float weight, bool gradients) {
  const gpu::Buffer& counts = counted_planes(cmd, f, gradients);
  const uint32_t F = uint32_t(f.u.size()), P = F - 1;
  const uint64_t quads = uint64_t(f.width) * f.height / 4;
  const uint32_t groups = gpu::Commands::div_up(quads, shaderio::kEventPairsGroupSize);
  const uint32_t columns = (shaderio::kEventPairsSumsPerPair * P + 3) / 4;
  partials_.ensure(uint64_t(columns) * groups * 16);
  sums_.ensure(uint64_t(columns) * 16);
  const shaderio::EventPairsPC pc = pairs_constants(f, weight, groups);
  const std::string suffix = "_f" + std::to_string(F);
  std::vector<gpu::Bind> binds = {{shaderio::kEventPairsBindCounts, counts},
                                  {shaderio::kEventPairsBindPartials, partials_}};
  for (uint32_t k = 0; k < F; ++k) binds.push_back({shaderio::kEventPairsBindFrames[k], *f.rgb[k]});
  cmd.dispatch("loss/event_pairs" + suffix, binds, pc, cmd.linear_groups(groups));

  record_event_columns(cmd, partials_, sums_, groups, columns);
  cmd.dispatch("loss/event_pairs_value",
               {{shaderio::kEventPairsValueBindSums, sums_},
                {shaderio::kEventPairsValueBindValues, value_buffer()},
                {shaderio::kEventPairsValueBindReversed, reversed_out_ ? *reversed_out_ : value_buffer()}},
               pc, gpu::Groups{1, 1, 1});
  if (!gradients) return;
  check_folded(f);
  const bool decode = !f.render_grad.empty();
  binds = {{shaderio::kEventPairsBindCounts, counts}, {shaderio::kEventPairsBwdBindSums, sums_}};
  for (uint32_t k = 0; k < F; ++k) {
    binds.insert(binds.end(),
                 {{shaderio::kEventPairsBindFrames[k], *f.rgb[k]},
                  {shaderio::kEventPairsBwdBindGrads[k], decode ? *f.render_grad[k] : *f.grad[k]},
                  {shaderio::kEventPairsBwdBindGradIns[k], f.grad_in.empty() ? *f.grad[k] : *f.grad_in[k]}});
  }
  cmd.dispatch("loss/event_pairs_bwd" + suffix + (decode ? "_decode" : ""), binds, pc, cmd.linear_groups(groups));
}

// The folded gradient plumbing's buffers (ExposureFrames): one per frame, each 3 x H x W floats.
void EventLoss::check_folded(const ExposureFrames& f) const {
  const size_t F = f.u.size();
  const uint64_t bytes = uint64_t(f.width) * f.height * 12;
  if ((!f.grad_in.empty() && f.grad_in.size() != F) || (!f.render_grad.empty() && f.render_grad.size() != F))
    throw std::invalid_argument("event loss: " + std::to_string(F) + " frames but " + std::to_string(f.grad_in.size()) +
                                " starting gradients and " + std::to_string(f.render_grad.size()) +
                                " render gradients");
  for (size_t i = 0; i < F; ++i)
    if ((!f.grad_in.empty() && f.grad_in[i]->size() < bytes) ||
        (!f.render_grad.empty() && f.render_grad[i]->size() < bytes))
      throw std::invalid_argument("event loss: frame " + std::to_string(i) +
                                  " starting gradient or render gradient holds less than 3 x H x W floats");
}

}  // namespace evflow
