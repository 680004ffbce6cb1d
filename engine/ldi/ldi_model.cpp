#include "ldi/ldi_model.h"

#include <algorithm>
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

// The activations (and their gradients) one chunk of calls may hold.
constexpr uint64_t kLdiActivationBytes = 256ull << 20;

}  // namespace

uint32_t LdiModel::batch_for(const gpu::Context& ctx, const std::vector<uint32_t>& widths, uint32_t crop_w,
                             uint32_t crop_h, uint32_t max_frames) {
  const uint64_t pixels = uint64_t(crop_w) * crop_h;
  const uint64_t by_memory =
      kLdiActivationBytes / std::max<uint64_t>(nn::ConvStack::bytes_per_image(widths, crop_h, crop_w), 1);
  const uint64_t by_binding =
      ctx.caps().max_storage_buffer_range / std::max<uint64_t>(uint64_t(nn::ConvStack::widest(widths)) * pixels * 4, 1);
  return uint32_t(std::max<uint64_t>(1, std::min<uint64_t>({2ull * max_frames, by_memory, by_binding})));
}

LdiModel::LdiModel(gpu::Context& ctx, const GpuEvents& events, const std::vector<uint32_t>& widths, uint32_t crop_w,
                   uint32_t crop_h, uint32_t max_frames, uint32_t max_batch)
    : ctx_(ctx),
      events_(events),
      widths_(checked_widths(widths)),
      crop_w_(crop_w),
      crop_h_(crop_h),
      max_frames_(max_frames),
      net_(ctx, widths, crop_h, crop_w, "ldi",
           std::min(batch_for(ctx, widths, crop_w, crop_h, max_frames), max_batch ? max_batch : ~0u)),
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

uint32_t LdiModel::call_of(uint32_t i, Side side) const {
  for (uint32_t c = 0; c < calls_.size(); ++c)
    if (calls_[c].frame == i && calls_[c].side == side) return c;
  return shaderio::kLdiNoSide;
}

uint32_t LdiModel::chunk_size(uint32_t first) const {
  return std::min<uint32_t>(batch(), uint32_t(calls_.size()) - first);
}

// Calls first .. first + chunk_size - 1: their event tensors into the network's input, one
// forward over them.
void LdiModel::run_chunk(gpu::Commands& cmd, uint32_t first) {
  const uint32_t n = chunk_size(first);
  const uint64_t values = uint64_t(n) * shaderio::kLdiChannels * pixels();
  cmd.fill(net_.input().buffer(), 0u, 0, values * 4);
  for (uint32_t j = 0; j < n; ++j) {
    const Call& c = calls_[first + j];
    record_side_counts(cmd, events_, view_, times_[c.frame], c.side, crop_, net_.input().buffer(), j);
  }
  record_counts_to_float(cmd, net_.input().buffer(), values);
  cmd.mark("ldi event tensors");
  net_.forward(cmd, "ldi conv", n);
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
  calls_.clear();
  for (uint32_t i = 0; i < frames(); ++i)
    for (Side side : {Side::Before, Side::After})
      if (weight(i, side) != 0) calls_.push_back({i, side});
  const uint64_t plane = pixels() * 4;
  for (uint32_t first = 0; first < calls_.size(); first += batch()) {
    run_chunk(cmd, first);
    cmd.copy(net_.output().buffer(), sides_, chunk_size(first) * plane, 0, first * plane);
  }
  for (uint32_t i = 0; i < frames(); ++i) combine(cmd, i);
}

shaderio::LdiCombinePC LdiModel::combine_pc(uint32_t i, uint32_t mode, float scale, float anchor) const {
  return {uint32_t(pixels()),
          i,
          float(weight(i, Side::Before)),
          float(weight(i, Side::After)),
          mode,
          scale,
          call_of(i, Side::Before),
          call_of(i, Side::After),
          anchor,
          0,
          0,
          0};
}

void LdiModel::combine(gpu::Commands& cmd, uint32_t i) {
  cmd.dispatch("ldi/combine",
               {{shaderio::kLdiCombineBindSides, sides_},
                {shaderio::kLdiCombineBindBlurry, *blurry_},
                {shaderio::kLdiCombineBindIntegral, integral_},
                {shaderio::kLdiCombineBindFrames, frames_buf_[i]}},
               combine_pc(i, 0, 1.0f), cmd.linear_groups(gpu::Commands::div_up(pixels(), shaderio::kLdiGroupSize)));
}

// Without an anchor its binding holds `grads` (never read).
void LdiModel::combine_bwd(gpu::Commands& cmd, uint32_t i, uint32_t mode, const gpu::Buffer& grads, float scale,
                           const LdiAnchor& anchor) {
  cmd.dispatch("ldi/combine_bwd",
               {{shaderio::kLdiCombineBwdBindSides, sides_},
                {shaderio::kLdiCombineBwdBindBlurry, *blurry_},
                {shaderio::kLdiCombineBwdBindGrads, grads},
                {shaderio::kLdiCombineBwdBindSideGrads, side_grads_},
                {shaderio::kLdiCombineBwdBindAnchor, anchor.target ? *anchor.target : grads}},
               combine_pc(i, mode, scale, anchor.target ? anchor.scale : 0.0f),
               cmd.linear_groups(gpu::Commands::div_up(pixels(), shaderio::kLdiGroupSize)));
}

void LdiModel::require_planes(const gpu::Buffer& b, uint32_t planes, const std::string& what) const {
  if (b.size() < planes * pixels() * 4)
    throw std::invalid_argument("LDI: " + what + " holds fewer than " + std::to_string(planes) + " planes");
}

void LdiModel::backward_from_frames(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads, float scale,
                                    const LdiAnchor& anchor) {
  if (!blurry_) throw std::logic_error("LDI: backward before forward");
  if (frame_grads.size() != frames())
    throw std::invalid_argument("LDI: " + std::to_string(frame_grads.size()) + " frame gradients for " +
                                std::to_string(frames()) + " frames");
  if (anchor.target) require_planes(*anchor.target, frames(), "the anchor");
  for (uint32_t i = 0; i < frames(); ++i) {
    require_planes(*frame_grads[i], 3, "frame gradient " + std::to_string(i));
    combine_bwd(cmd, i, shaderio::kLdiFromFrames, *frame_grads[i], scale, anchor);
  }
  backward_calls(cmd);
}

void LdiModel::backward_from_target(gpu::Commands& cmd, const gpu::Buffer& target, float scale) {
  if (!blurry_) throw std::logic_error("LDI: backward before forward");
  require_planes(target, frames(), "the target");
  for (uint32_t i = 0; i < frames(); ++i) combine_bwd(cmd, i, shaderio::kLdiFromTarget, target, scale);
  backward_calls(cmd);
}

// Chunk by chunk from the last, whose activations the forward left in the network; every other
// chunk's forward runs again first. The sides' gradients were recorded before.
void LdiModel::backward_calls(gpu::Commands& cmd) {
  const uint64_t plane = pixels() * 4;
  const uint32_t count = uint32_t(calls_.size());
  if (count == 0) return;
  const uint32_t last = (count - 1) / batch() * batch();
  for (uint32_t first = last;; first -= batch()) {
    if (first != last) run_chunk(cmd, first);
    cmd.copy(side_grads_, net_.output_grad().buffer(), chunk_size(first) * plane, first * plane, 0);
    cmd.mark("ldi side gradients");
    net_.backward(cmd, false, first != last, "ldi conv backward", chunk_size(first));
    if (first == 0) break;
  }
}

}  // namespace evflow::ldi
