#include "loss/warped_event_loss.h"

#include <stdexcept>
#include <string>

#include "loss/event_sums.h"
#include "loss/loss_layout.h"

namespace evflow {

namespace {

shaderio::WarpedEventPC warped_pc(uint32_t width, uint32_t height, uint32_t interval, uint32_t intervals,
                                  uint32_t value_index, const WarpedEventOptions& o, float weight) {
  const uint64_t hw = uint64_t(width) * height;
  shaderio::WarpedEventPC pc{};
  pc.width = width;
  pc.height = height;
  pc.interval = interval;
  pc.value_index = value_index;
  pc.eps = o.eps;
  pc.norm_floor2 = float(double(o.norm_floor_rms) * o.norm_floor_rms * double(hw));
  pc.grad_scale = weight / float(intervals);
  pc.value_scale = 1.0f / float(intervals);
  pc.value_accumulate = interval > 0 ? 1u : 0u;
  pc.pool = o.pool;
  return pc;
}

}  // namespace

WarpedEventLoss::WarpedEventLoss(gpu::Context& ctx, uint32_t width, uint32_t height,
                                 const std::vector<std::vector<float>>& planes, float weight,
                                 WarpedEventOptions options)
    : ExposureLossTerm(ctx, "events_warped", weight, 1),
      width_(width),
      height_(height),
      options_(options),
      scratch_(ctx, 16, "warped_scratch"),
      partials_(ctx, 16, "warped_partials"),
      sums_(ctx, 16, "warped_sums") {
  if (!(options.eps > 0)) throw std::invalid_argument("warped-event loss: eps must be > 0");
  if (!(options.norm_floor_rms > 0)) throw std::invalid_argument("warped-event loss: norm_floor_rms must be > 0");
  check_event_pool(options.pool, "warped-event loss");
  const size_t hw = size_t(width) * height;
  if (planes.empty() || hw == 0) throw std::invalid_argument("warped-event loss: no views or an empty image");
  if (planes[0].size() % (3 * hw) != 0 || planes[0].empty())
    throw std::invalid_argument("warped-event loss: view 0's planes are not a whole number of intervals");
  intervals_ = uint32_t(planes[0].size() / (3 * hw));
  for (size_t v = 0; v < planes.size(); ++v) {
    if (planes[v].size() != planes[0].size())
      throw std::invalid_argument("warped-event loss: view " + std::to_string(v) + " has " +
                                  std::to_string(planes[v].size()) + " plane values, view 0 has " +
                                  std::to_string(planes[0].size()));
    ctx.check_binding_size(planes[v].size() * 4, "warped-event planes");
    planes_.emplace_back(ctx, planes[v].size() * 4, "warped_planes");
    planes_.back().write(planes[v]);
  }
  const uint64_t cells = event_pool_cells(width, height, options.pool);
  cell_groups_ = gpu::Commands::div_up(cells, shaderio::kLossGroupSize);
  scratch_ = gpu::Buffer(ctx, 2 * cells * 4, "warped_scratch");
  partials_ = gpu::Buffer(ctx, uint64_t(cell_groups_) * 16, "warped_partials");
  sums_ = gpu::Buffer(ctx, uint64_t(intervals_) * 16, "warped_sums");
}

void WarpedEventLoss::check(const ExposureFrames& f) const {
  if (f.u.size() != intervals_ + 1 || f.rgb.size() != f.u.size() || f.grad.size() != f.u.size())
    throw std::invalid_argument("warped-event loss: " + std::to_string(intervals_) + " intervals need " +
                                std::to_string(intervals_ + 1) + " frames, got " + std::to_string(f.u.size()) +
                                " times, " + std::to_string(f.rgb.size()) + " renders and " +
                                std::to_string(f.grad.size()) + " gradient images");
  if (f.width != width_ || f.height != height_)
    throw std::invalid_argument("warped-event loss: frames are " + std::to_string(f.width) + "x" +
                                std::to_string(f.height) + " but the warped events are " + std::to_string(width_) +
                                "x" + std::to_string(height_));
  check_view(f.view);
}

void WarpedEventLoss::check_view(uint32_t view) const {
  if (view >= planes_.size())
    throw std::invalid_argument("warped-event loss: view " + std::to_string(view) + " has no warped events");
}

void WarpedEventLoss::set_view_planes(uint32_t view, const std::vector<float>& planes) {
  check_view(view);
  if (planes.size() * 4 != planes_[view].size())
    throw std::invalid_argument("warped-event loss: view " + std::to_string(view) + " gets " +
                                std::to_string(planes.size()) + " plane values, it has " +
                                std::to_string(planes_[view].size() / 4));
  planes_[view].write(planes);
}

std::pair<std::vector<float>, std::vector<float>> WarpedEventLoss::compared(gpu::Commands& cmd, uint32_t view,
                                                                            uint32_t interval,
                                                                            const gpu::Buffer& frame) {
  check_view(view);
  if (interval >= intervals_)
    throw std::invalid_argument("warped-event loss: interval " + std::to_string(interval) + " of " +
                                std::to_string(intervals_));
  record_forward(cmd, view, interval, frame, 0.0f);
  cmd.submit();
  const uint32_t pool = options_.pool, cw = (width_ + pool - 1) / pool;
  const uint64_t cells = event_pool_cells(width_, height_, pool), hw = uint64_t(width_) * height_;
  const std::vector<float> both = scratch_.read<float>(2 * cells);
  std::pair<std::vector<float>, std::vector<float>> out{std::vector<float>(hw), std::vector<float>(hw)};
  for (uint32_t y = 0; y < height_; ++y)  // each pixel shows its pooling cell's value
    for (uint32_t x = 0; x < width_; ++x) {
      const uint64_t c = uint64_t(y / pool) * cw + x / pool;
      out.first[uint64_t(y) * width_ + x] = both[c];
      out.second[uint64_t(y) * width_ + x] = both[cells + c];
    }
  return out;
}

void WarpedEventLoss::record_forward(gpu::Commands& cmd, uint32_t view, uint32_t interval, const gpu::Buffer& frame,
                                     float weight) {
  cmd.dispatch("loss/warped_event",
               {{shaderio::kWarpedEventBindPlanes, planes_[view]},
                {shaderio::kWarpedEventBindFrame, frame},
                {shaderio::kWarpedEventBindScratch, scratch_},
                {shaderio::kWarpedEventBindPartials, partials_}},
               warped_pc(width_, height_, interval, intervals_, value_offset(), options_, weight),
               cmd.linear_groups(cell_groups_));
}

void WarpedEventLoss::record(gpu::Commands& cmd, const ExposureFrames& f, float weight) {
  check(f);
  const uint64_t hw = uint64_t(width_) * height_;
  const uint32_t groups = gpu::Commands::div_up(hw, shaderio::kLossGroupSize);
  const gpu::Groups g = cmd.linear_groups(groups);
  const gpu::Buffer& planes = planes_[f.view];
  for (uint32_t i = 0; i < intervals_; ++i) {
    const shaderio::WarpedEventPC pc = warped_pc(width_, height_, i, intervals_, value_offset(), options_, weight);
    record_forward(cmd, f.view, i, *f.rgb[i + 1], weight);
    record_event_sums(cmd, partials_, sums_, cell_groups_, 4 * i);
    cmd.dispatch("loss/warped_event_bwd",
                 {{shaderio::kWarpedEventBwdBindPlanes, planes},
                  {shaderio::kWarpedEventBwdBindFrame, *f.rgb[i + 1]},
                  {shaderio::kWarpedEventBwdBindScratch, scratch_},
                  {shaderio::kWarpedEventBwdBindSums, sums_},
                  {shaderio::kWarpedEventBwdBindGrad, *f.grad[i + 1]},
                  {shaderio::kWarpedEventBwdBindValues, value_buffer()}},
                 pc, g);
  }
}

}  // namespace evflow
