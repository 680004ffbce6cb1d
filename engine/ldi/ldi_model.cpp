#include "ldi/ldi_model.h"

#include <cmath>
#include <stdexcept>

#include "ldi/ldi_layout.h"

namespace evflow::ldi {

float neutral_bias() { return float(std::log(std::expm1(1.0 - double(shaderio::kLdiFloor)))); }

namespace {

const std::vector<uint32_t>& checked_widths(const std::vector<uint32_t>& widths) {
  if (widths.size() < 2 || widths.front() != shaderio::kLdiChannels || widths.back() != 1)
    throw std::invalid_argument("LDI: the widths must start with 32 (16 bins x 2 polarities) and end with 1");
  for (uint32_t w : widths)
    if (w == 0) throw std::invalid_argument("LDI: a layer of width 0");
  return widths;
}

}  // namespace

LdiModel::LdiModel(gpu::Context& ctx, const GpuEvents& events, const std::vector<uint32_t>& widths, uint32_t crop_w,
                   uint32_t crop_h, uint32_t max_frames)
    : ctx_(ctx),
      events_(events),
      widths_(checked_widths(widths)),
      crop_w_(crop_w),
      crop_h_(crop_h),
      max_frames_(max_frames),
      net_(ctx, widths, crop_h, crop_w, "ldi"),
      sides_(ctx, 2ull * max_frames * crop_w * crop_h * 4, "ldi_sides"),
      side_grads_(ctx, 2ull * max_frames * crop_w * crop_h * 4, "ldi_side_grads"),
      integral_(ctx, uint64_t(max_frames) * crop_w * crop_h * 4, "ldi_integral") {
  if (max_frames == 0) throw std::invalid_argument("LDI: no frames");
  check_crop({0, 0, crop_w, crop_h}, events.width(), events.height(), "LDI");
  ctx.check_binding_size(2ull * max_frames * crop_w * crop_h * 4, "LDI side outputs");
  for (uint32_t i = 0; i < max_frames; ++i) frames_buf_.emplace_back(ctx, 3ull * crop_w * crop_h * 4, "ldi_frame");
}

void LdiModel::init(uint64_t seed) {
  net_.init_he(seed);
  nn::Conv2d& last = net_.layer(net_.layers() - 1);
  last.set_parameters(last.weight_values(), std::vector<float>(1, neutral_bias()));
}

double LdiModel::weight(uint32_t i, Side side) const {
  const EventWindow& win = events_.window(view_);
  const double u = (times_[i] - win.t0) / (win.t1 - win.t0);
  return side == Side::Before ? u : 1.0 - u;
}

// One network call: the side's events into the input, the forward pass.
void LdiModel::run_call(gpu::Commands& cmd, const Call& c) {
  record_side_tensor(cmd, events_, view_, times_[c.frame], c.side, crop_, net_.input().buffer());
  net_.forward(cmd);
}

void LdiModel::forward(gpu::Commands& cmd, size_t view, const std::vector<double>& times, const Crop& crop,
                       const gpu::Buffer& blurry) {
  if (times.empty() || times.size() > max_frames_)
    throw std::invalid_argument("LDI: " + std::to_string(times.size()) + " frame times for a model of at most " +
                                std::to_string(max_frames_) + " frames");
  if (view >= events_.window_count())
    throw std::invalid_argument("LDI: view " + std::to_string(view) + " has no event window");
  for (double t : times) side_bounds(events_, view, t, Side::After);  // throws for a time outside the window
  if (crop.w != crop_w_ || crop.h != crop_h_)
    throw std::invalid_argument("LDI: a " + std::to_string(crop.w) + "x" + std::to_string(crop.h) +
                                " crop for a model of " + std::to_string(crop_w_) + "x" + std::to_string(crop_h_));
  if (blurry.size() < 3 * pixels() * 4) throw std::invalid_argument("LDI: the blurry crop holds fewer than 3 planes");
  view_ = view, crop_ = crop, times_ = times, blurry_ = &blurry;
  const uint64_t plane = pixels() * 4;
  for (uint32_t i = 0; i < frames(); ++i) {
    for (Side side : {Side::Before, Side::After}) {
      const uint64_t at = (2 * i + (side == Side::After ? 1 : 0)) * plane;
      if (weight(i, side) == 0) {
        cmd.fill(sides_, 0u, at, plane);
        continue;
      }
      run_call(cmd, {i, side});
      cmd.copy(net_.output().buffer(), sides_, plane, 0, at);
    }
    combine(cmd, i);
  }
}

shaderio::LdiCombinePC LdiModel::combine_pc(uint32_t i, uint32_t mode, float scale) const {
  return {uint32_t(pixels()), i, float(weight(i, Side::Before)), float(weight(i, Side::After)), mode, scale, 0, 0};
}

void LdiModel::combine(gpu::Commands& cmd, uint32_t i) {
  cmd.dispatch("ldi/combine",
               {{shaderio::kLdiCombineBindSides, sides_},
                {shaderio::kLdiCombineBindBlurry, *blurry_},
                {shaderio::kLdiCombineBindIntegral, integral_},
                {shaderio::kLdiCombineBindFrames, frames_buf_[i]}},
               combine_pc(i, 0, 1.0f), cmd.linear_groups(gpu::Commands::div_up(pixels(), shaderio::kLdiGroupSize)));
}

void LdiModel::combine_bwd(gpu::Commands& cmd, uint32_t i, uint32_t mode, const gpu::Buffer& grads, float scale) {
  cmd.dispatch("ldi/combine_bwd",
               {{shaderio::kLdiCombineBwdBindSides, sides_},
                {shaderio::kLdiCombineBwdBindBlurry, *blurry_},
                {shaderio::kLdiCombineBwdBindGrads, grads},
                {shaderio::kLdiCombineBwdBindSideGrads, side_grads_}},
               combine_pc(i, mode, scale), cmd.linear_groups(gpu::Commands::div_up(pixels(), shaderio::kLdiGroupSize)));
}

void LdiModel::backward_from_frames(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads,
                                    float scale) {
  if (!blurry_) throw std::logic_error("LDI: backward before forward");
  if (frame_grads.size() != frames())
    throw std::invalid_argument("LDI: " + std::to_string(frame_grads.size()) + " frame gradients for " +
                                std::to_string(frames()) + " frames");
  for (uint32_t i = 0; i < frames(); ++i) {
    if (frame_grads[i]->size() < 3 * pixels() * 4)
      throw std::invalid_argument("LDI: frame gradient " + std::to_string(i) + " holds fewer than 3 planes");
    combine_bwd(cmd, i, shaderio::kLdiFromFrames, *frame_grads[i], scale);
  }
  backward_calls(cmd);
}

void LdiModel::backward_from_target(gpu::Commands& cmd, const gpu::Buffer& target, float scale) {
  if (!blurry_) throw std::logic_error("LDI: backward before forward");
  if (target.size() < frames() * pixels() * 4) throw std::invalid_argument("LDI: the target holds fewer than F planes");
  for (uint32_t i = 0; i < frames(); ++i) combine_bwd(cmd, i, shaderio::kLdiFromTarget, target, scale);
  backward_calls(cmd);
}

// Each call again (the sides' gradients recorded before): forward, its output's gradient, backward.
void LdiModel::backward_calls(gpu::Commands& cmd) {
  const uint64_t plane = pixels() * 4;
  bool first = true;
  for (uint32_t i = 0; i < frames(); ++i)
    for (Side side : {Side::Before, Side::After}) {
      if (weight(i, side) == 0) continue;
      run_call(cmd, {i, side});
      cmd.copy(side_grads_, net_.output_grad().buffer(), plane, (2 * i + (side == Side::After ? 1 : 0)) * plane, 0);
      net_.backward(cmd, false, !first);
      first = false;
    }
}

}  // namespace evflow::ldi
