#include "loss/warped_event_loss.h"

#include <stdexcept>
#include <string>

#include "loss/loss_layout.h"

namespace evflow {

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
  scratch_ = gpu::Buffer(ctx, 2 * cells * 4, "warped_scratch");
  partials_ =
      gpu::Buffer(ctx, uint64_t(gpu::Commands::div_up(cells, shaderio::kLossGroupSize)) * 16, "warped_partials");
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
  if (f.view >= planes_.size())
    throw std::invalid_argument("warped-event loss: view " + std::to_string(f.view) + " has no warped events");
}

void WarpedEventLoss::record(gpu::Commands& cmd, const ExposureFrames& f, float weight) {
  check(f);
  const uint64_t hw = uint64_t(width_) * height_;
  const uint32_t groups = gpu::Commands::div_up(hw, shaderio::kLossGroupSize);
  const uint32_t cell_groups =
      gpu::Commands::div_up(event_pool_cells(width_, height_, options_.pool), shaderio::kLossGroupSize);
  const gpu::Groups g = cmd.linear_groups(groups), gc = cmd.linear_groups(cell_groups);
  const gpu::Buffer& planes = planes_[f.view];
  for (uint32_t i = 0; i < intervals_; ++i) {
    shaderio::WarpedEventPC pc{};
    pc.width = width_;
    pc.height = height_;
    pc.interval = i;
    pc.value_index = value_offset();
    pc.eps = options_.eps;
    pc.norm_floor2 = float(double(options_.norm_floor_rms) * options_.norm_floor_rms * double(hw));
    pc.grad_scale = weight / float(intervals_);
    pc.value_scale = 1.0f / float(intervals_);
    pc.value_accumulate = i > 0 ? 1u : 0u;
    pc.pool = options_.pool;
    cmd.dispatch("loss/warped_event",
                 {{shaderio::kWarpedEventBindPlanes, planes},
                  {shaderio::kWarpedEventBindFrame, *f.rgb[i + 1]},
                  {shaderio::kWarpedEventBindScratch, scratch_},
                  {shaderio::kWarpedEventBindPartials, partials_}},
                 pc, gc);
    shaderio::ReducePC r{};
    r.coeff0 = glm::vec4(1, 0, 0, 0);
    r.coeff1 = glm::vec4(0, 1, 0, 0);
    r.coeff2 = glm::vec4(0, 0, 1, 0);
    r.n_partials = cell_groups;
    r.dst = 4 * i;
    r.n_out = 3;
    cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials_}, {shaderio::kReduceBindOut, sums_}}, r,
                 gpu::Groups{1, 1, 1});
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
