#include "flow/flow_estimator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "flow/flow_layout.h"
#include "optim/host_adam.h"

namespace evflow::flow {

using shaderio::kFlowGroupSize;
using shaderio::kFlowRefs;

namespace {
constexpr double kRefWeight[kFlowRefs] = {0.25, 0.5, 0.25};  // flow_ref_weight() gives them out
}

void FlowOptions::validate() const {
  if (tiles.empty() || tiles.size() != iterations.size())
    throw std::invalid_argument("flow: the tile pyramid and the iterations per level must be non-empty and as long");
  for (size_t l = 0; l < tiles.size(); ++l)
    if (tiles[l] == 0 || tiles[l] > 256 || (l > 0 && tiles[l] % tiles[l - 1] != 0))
      throw std::invalid_argument("flow: tiles per level must be 1..256, each a multiple of the one before");
  if (image_scale.size() != tiles.size() || event_stride.size() != tiles.size())
    throw std::invalid_argument("flow: one image scale and one event stride per level of the tile pyramid");
  for (uint32_t st : event_stride)
    if (st == 0) throw std::invalid_argument("flow: event strides must be >= 1");
  if (time_groups.size() != time_iterations.size())
    throw std::invalid_argument("flow: one iteration count per grouping of the intervals");
  for (uint32_t g : time_groups)
    if (g == 0) throw std::invalid_argument("flow: interval groups must be >= 1");
  if (interval_event_stride == 0) throw std::invalid_argument("flow: interval_event_stride must be >= 1");
  for (uint32_t sc : image_scale)
    if (sc == 0 || sc > 64) throw std::invalid_argument("flow: image scales must be 1..64");
  if (!(lr > 0) || !(lr_level > 0)) throw std::invalid_argument("flow: learning rates must be > 0");
  if (!(tv_weight >= 0)) throw std::invalid_argument("flow: tv_weight must be >= 0");
}

double flow_ref_weight(uint32_t r) { return kRefWeight[r]; }

namespace {
// The intervals between consecutive frame times as the shaders read them.
std::vector<float> interval_table(const std::vector<double>& frame_u) {
  if (frame_u.size() < 2 || frame_u.size() > shaderio::kFlowMaxIntervals + 1)
    throw std::invalid_argument("flow: needs 2 to " + std::to_string(shaderio::kFlowMaxIntervals + 1) +
                                " frame times, got " + std::to_string(frame_u.size()));
  std::vector<float> t;
  for (size_t i = 0; i + 1 < frame_u.size(); ++i) {
    const double d = frame_u[i + 1] - frame_u[i];
    if (!(d > 0) || frame_u[i] < 0 || frame_u[i + 1] > 1)
      throw std::invalid_argument("flow: frame times must increase within [0, 1]");
    t.insert(t.end(), {float(frame_u[i]), float(frame_u[i + 1]), float(1.0 / d), 0.0f});
  }
  return t;
}
}  // namespace

FlowEstimator::FlowEstimator(gpu::Context& ctx, FlowOptions options)
    : ctx_(ctx),
      options_(std::move(options)),
      pixel_first_(ctx, 16, "flow_pixel_first"),
      pixel_order_(ctx, 16, "flow_pixel_order"),
      event_time_(ctx, 16, "flow_event_time"),
      event_slot_(ctx, 16, "flow_event_slot"),
      intervals_(ctx, 16, "flow_intervals"),
      nodes_(ctx, 16, "flow_nodes"),
      iwe_(ctx, 16, "flow_iwe"),
      blur_tmp_(ctx, 16, "flow_blur_tmp"),
      blurred_(ctx, 16, "flow_blurred"),
      adjoint_(ctx, 16, "flow_adjoint"),
      scale_(ctx, 16, "flow_scale"),
      partials_(ctx, 16, "flow_partials"),
      quads_(ctx, 16, "flow_adjoint_quads"),
      positions_(ctx, 16, "flow_positions"),
      grad_field_(ctx, 16, "flow_grad_field"),
      tile_grad_(ctx, 16, "flow_tile_grad") {
  options_.validate();
}

void FlowEstimator::set_events(const PixelEvents& ev) {
  const uint64_t hw = uint64_t(ev.width) * ev.height;
  if (hw == 0 || ev.first.size() != hw + 1 || ev.first.back() != ev.size())
    throw std::invalid_argument("flow: pixel events are inconsistent with their " + std::to_string(ev.width) + "x" +
                                std::to_string(ev.height) + " sensor");
  ctx_.check_binding_size(ev.size() * 4, "flow: the events of one exposure");
  width_ = ev.width;
  height_ = ev.height;
  pixel_first_.ensure((hw + 1) * 4);
  pixel_first_.write(ev.first);
  event_time_.ensure(std::max<uint64_t>(ev.size() * 4, 16));
  event_time_.write(ev.time);
  if (ev.order.size() > hw) throw std::invalid_argument("flow: pixel order longer than the sensor");
  pixel_order_.ensure(std::max<uint64_t>(ev.order.size() * 4, 16));
  pixel_order_.write(ev.order);
  busy_pixels_ = uint32_t(ev.order.size());
  grad_field_zeroed_ = 0;
  events_ = uint32_t(ev.size());
  std::vector<uint32_t> slot(std::max<size_t>(ev.size(), 1), 0);  // each event's pixel's index in order
  for (uint32_t k = 0; k < busy_pixels_; ++k)
    for (uint32_t e = ev.first[ev.order[k]]; e < ev.first[ev.order[k] + 1]; ++e) slot[e] = k;
  event_slot_.ensure(slot.size() * 4);
  event_slot_.write(slot);
  const uint64_t positions = std::max<uint64_t>(busy_pixels_, 1) * shaderio::kFlowPositionsPerPixel * 8;
  ctx_.check_binding_size(positions, "flow: the positions of the pixels with events");
  positions_.ensure(positions);
}

void FlowEstimator::record_contrast(gpu::Commands& cmd, uint32_t intervals, uint32_t tiles, uint32_t image_scale,
                                    uint32_t stride, bool gradient) {
  using namespace shaderio;
  const uint32_t iw = (width_ + image_scale - 1) / image_scale, ih = (height_ + image_scale - 1) / image_scale;
  const uint64_t hw = uint64_t(iw) * ih;
  const FlowEventsPC epc{width_,       height_, intervals, tiles, iw, ih, float(image_scale),
                         busy_pixels_, stride,  events_,   0,     0};
  const gpu::Groups pixel_groups = cmd.linear_groups(std::max(1u, gpu::Commands::div_up(busy_pixels_, kFlowGroupSize)));
  const gpu::Groups image_groups = cmd.linear_groups(gpu::Commands::div_up(hw * kFlowRefs, kFlowGroupSize));
  const uint32_t per_image = gpu::Commands::div_up(hw, kFlowGroupSize);
  cmd.dispatch("flow/positions",
               {{kFlowPositionsBindPixelOrder, pixel_order_},
                {kFlowPositionsBindIntervals, intervals_},
                {kFlowPositionsBindNodes, nodes_},
                {kFlowPositionsBindPositions, positions_}},
               epc, pixel_groups);
  cmd.mark("positions");
  cmd.fill(iwe_, 0u, 0, hw * kFlowRefs * 4);
  cmd.dispatch(
      "flow/vote",
      {{kFlowVoteBindPixelOrder, pixel_order_},
       {kFlowVoteBindEventSlot, event_slot_},
       {kFlowVoteBindEventTime, event_time_},
       {kFlowVoteBindIntervals, intervals_},
       {kFlowVoteBindPositions, positions_},
       {kFlowVoteBindIwe, iwe_}},
      epc,
      cmd.linear_groups(std::max(1u, gpu::Commands::div_up(gpu::Commands::div_up(events_, stride), kFlowGroupSize))));
  cmd.mark("vote");
  auto blur = [&](const gpu::Buffer& src, const gpu::Buffer& dst, uint32_t axis, uint32_t fixed) {
    const FlowBlurPC bpc{iw, ih, kFlowRefs, axis, fixed, 0, 0, 0};
    cmd.dispatch("flow/blur", {{kFlowBlurBindSrc, src}, {kFlowBlurBindDst, dst}}, bpc, image_groups);
  };
  blur(iwe_, blur_tmp_, 0, 1);
  blur(blur_tmp_, blurred_, 1, 0);
  cmd.mark("blur");
  const FlowContrastPC cpc{iw, ih, kFlowRefs, per_image};
  cmd.dispatch("flow/contrast",
               {{kFlowContrastBindBlurred, blurred_},
                {kFlowContrastBindScale, scale_},
                {kFlowContrastBindAdjoint, adjoint_},
                {kFlowContrastBindPartials, partials_}},
               cpc, cmd.linear_groups(uint64_t(per_image) * kFlowRefs));
  cmd.mark("contrast");
  if (!gradient) return;
  blur(adjoint_, blur_tmp_, 0, 0);  // the blur is its own adjoint
  blur(blur_tmp_, adjoint_, 1, 0);
  cmd.mark("blur");
  const FlowQuadsPC qpc{iw, ih, kFlowRefs, 0};
  cmd.dispatch("flow/adjoint_quads", {{kFlowQuadsBindAdjoint, adjoint_}, {kFlowQuadsBindQuads, quads_}}, qpc,
               cmd.linear_groups(gpu::Commands::div_up(uint64_t(iw + 1) * (ih + 1) * kFlowRefs, kFlowGroupSize)));
  cmd.mark("adjoint quads");
  if (grad_field_zeroed_ != intervals) {  // pixels without events: zero until the events change
    cmd.fill(grad_field_, 0u, 0, uint64_t(width_) * height_ * intervals * 8);
    grad_field_zeroed_ = intervals;
  }
  cmd.dispatch("flow/flow_grad",
               {{kFlowGradBindPixelOrder, pixel_order_},
                {kFlowGradBindPixelFirst, pixel_first_},
                {kFlowGradBindEventTime, event_time_},
                {kFlowGradBindIntervals, intervals_},
                {kFlowGradBindPositions, positions_},
                {kFlowGradBindQuads, quads_},
                {kFlowGradBindGradField, grad_field_}},
               epc, pixel_groups);
  cmd.mark("flow gradient");
  const FlowNodeReducePC rpc{width_, height_, intervals, tiles};
  cmd.dispatch("flow/node_reduce", {{kFlowReduceBindGradField, grad_field_}, {kFlowReduceBindTileGrad, tile_grad_}},
               rpc, cmd.linear_groups(uint64_t(tiles) * tiles * intervals));
  cmd.mark("node reduce");
}

ContrastEval FlowEstimator::evaluate(const std::vector<double>& frame_u, const std::vector<FlowGrid>& grids,
                                     const std::vector<float>& scale, bool gradient, uint32_t image_scale,
                                     uint32_t stride) {
  const std::vector<float> table = interval_table(frame_u);
  const uint32_t J = uint32_t(grids.size());
  if (J != frame_u.size() - 1 || scale.size() != kFlowRefs)
    throw std::invalid_argument("flow: evaluate needs one grid per interval and three scales");
  if (width_ == 0) throw std::logic_error("flow: evaluate before set_events");
  const uint32_t tiles = grids[0].tiles;
  const uint64_t hw = uint64_t(width_) * height_;
  ctx_.check_binding_size(hw * kFlowRefs * 4, "flow: the images of warped events");
  ctx_.check_binding_size(hw * J * 8, "flow: the per-pixel flow gradients");
  std::vector<float> nodes;
  for (const FlowGrid& g : grids) {
    if (g.tiles != tiles) throw std::invalid_argument("flow: every grid of one evaluate has the same tiles");
    nodes.insert(nodes.end(), g.nodes.begin(), g.nodes.end());
  }
  if (image_scale == 0 || image_scale > 64) throw std::invalid_argument("flow: image scale must be 1..64");
  const uint64_t ihw = uint64_t((width_ + image_scale - 1) / image_scale) * ((height_ + image_scale - 1) / image_scale);
  const uint32_t per_image = uint32_t((ihw + kFlowGroupSize - 1) / kFlowGroupSize);
  last_image_pixels_ = ihw;
  intervals_.ensure(table.size() * 4);
  intervals_.write(table);
  nodes_.ensure(nodes.size() * 4);
  nodes_.write(nodes);
  scale_.ensure(kFlowRefs * 4);
  scale_.write(scale);
  for (gpu::Buffer* b : {&iwe_, &blur_tmp_, &blurred_, &adjoint_}) b->ensure(hw * kFlowRefs * 4);
  partials_.ensure(uint64_t(per_image) * kFlowRefs * 4);
  const uint64_t quads = uint64_t(width_ + 1) * (height_ + 1) * kFlowRefs * 16;
  ctx_.check_binding_size(quads, "flow: the adjoint footprints");
  quads_.ensure(quads);
  grad_field_.ensure(hw * J * 8);
  tile_grad_.ensure(uint64_t(tiles) * tiles * J * 4 * 8);

  gpu::Commands cmd(ctx_);
  if (stride == 0) throw std::invalid_argument("flow: event stride must be >= 1");
  record_contrast(cmd, J, tiles, image_scale, stride, gradient);
  cmd.submit();
  for (const auto& [name, ms] : cmd.stage_ms()) {
    auto it = std::find_if(stage_ms_.begin(), stage_ms_.end(), [&](const auto& s) { return s.first == name; });
    if (it == stage_ms_.end())
      stage_ms_.emplace_back(name, ms);
    else
      it->second += ms;
  }
  ++evaluations_;

  ContrastEval out;
  const std::vector<float> partials = partials_.read<float>(size_t(per_image) * kFlowRefs);
  out.g.assign(kFlowRefs, 0.0);
  for (uint32_t r = 0; r < kFlowRefs; ++r)
    for (uint32_t k = 0; k < per_image; ++k) out.g[r] += partials[r * per_image + k];
  if (gradient) {
    // Each tile's four corner sums onto its nodes, tile by tile in index order.
    const std::vector<float> t = tile_grad_.read<float>(size_t(tiles) * tiles * J * 8);
    const uint32_t side = tiles + 1;
    for (uint32_t j = 0; j < J; ++j) {
      std::vector<double> g(grids[0].nodes.size(), 0.0);
      for (uint32_t cell = 0; cell < tiles * tiles; ++cell) {
        const uint32_t a = cell % tiles, b = cell / tiles;
        const uint32_t corner[4] = {b * side + a, b * side + a + 1, (b + 1) * side + a, (b + 1) * side + a + 1};
        for (uint32_t c = 0; c < 4; ++c)
          for (uint32_t d = 0; d < 2; ++d)
            g[corner[c] * 2 + d] += t[((size_t(j) * tiles * tiles + cell) * 4 + c) * 2 + d];
      }
      out.node_grad.push_back(std::move(g));
    }
  }
  return out;
}

std::vector<float> FlowEstimator::iwe(uint32_t r) const {
  if (width_ == 0 || r >= kFlowRefs) throw std::out_of_range("flow: no such image of warped events");
  const uint64_t hw = uint64_t(width_) * height_;
  if (last_image_pixels_ != hw) throw std::logic_error("flow: the last evaluate was not at full resolution");
  std::vector<uint32_t> fixed = iwe_.read<uint32_t>(hw, uint64_t(r) * hw * 4);
  std::vector<float> out(hw);
  for (uint64_t i = 0; i < hw; ++i) out[i] = float(fixed[i] / double(shaderio::kFlowVoteScale));
  return out;
}

namespace {
// weight * mean over nodes and neighbouring intervals of |u_{j+1} - u_j|^2: its gradient, added.
void add_temporal_smoothness(const std::vector<FlowGrid>& grids, double weight,
                             std::vector<std::vector<double>>& grad) {
  const size_t n = grids[0].nodes.size();
  const double k = 2 * weight / (double(n / 2) * std::max<size_t>(1, grids.size() - 1));
  for (size_t j = 0; j + 1 < grids.size(); ++j)
    for (size_t i = 0; i < n; ++i) {
      const double d = double(grids[j + 1].nodes[i]) - grids[j].nodes[i];
      grad[j + 1][i] += k * d;
      grad[j][i] -= k * d;
    }
}
}  // namespace

void FlowEstimator::optimise_level(const std::vector<double>& frame_u, std::vector<FlowGrid>& grids,
                                   const std::vector<float>& scale, uint32_t iterations, double lr, uint32_t groups,
                                   uint32_t image_scale, uint32_t stride) {
  const size_t J = grids.size(), n = grids[0].nodes.size();
  auto group = [&](size_t j) { return j * groups / J; };  // neighbouring intervals share a group's flow
  std::vector<std::vector<double>> x(groups, std::vector<double>(n, 0.0)), m = x, v = x, grad = x;
  std::vector<size_t> members(groups, 0);
  for (size_t j = 0; j < J; ++j) {  // a group starts from the mean of its intervals' flows
    ++members[group(j)];
    for (size_t k = 0; k < n; ++k) x[group(j)][k] += grids[j].nodes[k];
  }
  for (size_t g = 0; g < groups; ++g)
    for (double& value : x[g]) value /= double(members[g]);
  auto write_grids = [&] {
    for (size_t j = 0; j < J; ++j)
      for (size_t k = 0; k < n; ++k) grids[j].nodes[k] = float(x[group(j)][k]);
  };
  write_grids();
  for (uint32_t it = 0; it < iterations; ++it) {
    ContrastEval e = evaluate(frame_u, grids, scale, true, image_scale, stride);
    const double step = lr * (1.0 - 0.9 * it / std::max(1u, iterations));  // decays to lr / 10
    if (groups > 1) add_temporal_smoothness(grids, options_.temporal_weight, e.node_grad);
    for (auto& g : grad) std::fill(g.begin(), g.end(), 0.0);
    for (size_t j = 0; j < J; ++j)  // the gradients of a group's intervals add
      for (size_t k = 0; k < n; ++k) grad[group(j)][k] += e.node_grad[j][k];
    for (size_t g = 0; g < groups; ++g) {
      grid_tv(grids[(g * J + groups - 1) / groups], options_.tv_weight * double(members[g]), grad[g]);
      host_adam_step(x[g].data(), grad[g].data(), m[g].data(), v[g].data(), n, it + 1, step);
    }
    write_grids();
  }
}

std::vector<float> FlowEstimator::normalisation(const std::vector<double>& frame_u, uint32_t tiles,
                                                uint32_t image_scale, uint32_t stride) {
  const std::vector<FlowGrid> zero(frame_u.size() - 1, FlowGrid(tiles));
  const ContrastEval e = evaluate(frame_u, zero, std::vector<float>(kFlowRefs, 0.0f), false, image_scale, stride);
  std::vector<float> scale(kFlowRefs, 0.0f);
  for (uint32_t r = 0; r < kFlowRefs; ++r)
    if (e.g[r] > 0) scale[r] = float(-kRefWeight[r] / e.g[r]);
  return scale;
}

ExposureFlow FlowEstimator::estimate(const PixelEvents& events, const std::vector<double>& frame_u) {
  set_events(events);
  const size_t J = interval_table(frame_u).size() / 4;
  std::vector<FlowGrid> grids(J, FlowGrid(options_.tiles[0]));
  double lr = options_.lr;
  for (size_t l = 0; l < options_.tiles.size(); ++l, lr *= options_.lr_level) {
    if (l > 0)
      for (FlowGrid& g : grids) g = refine(g, options_.tiles[l], events.width, events.height);
    const uint32_t sc = options_.image_scale[l], stride = options_.event_stride[l];
    const std::vector<float> scale = normalisation(frame_u, options_.tiles[l], sc, stride);
    optimise_level(frame_u, grids, scale, options_.iterations[l], lr, 1, sc, stride);
  }
  // Coarse to fine in time: neighbouring intervals tied in ever smaller groups, each grouping with
  // its own decaying step, then every interval on its own once more. The step is a fraction of the
  // sensor's diagonal: the same motion moves twice as many pixels on a sensor twice as large.
  const uint32_t stride = options_.interval_event_stride;
  const std::vector<float> scale = normalisation(frame_u, options_.tiles.back(), 1, stride);
  const double step = options_.lr_intervals * std::hypot(double(events.width), double(events.height));
  for (size_t l = 0; l < options_.time_groups.size(); ++l)
    optimise_level(frame_u, grids, scale, options_.time_iterations[l], step,
                   std::min<uint32_t>(options_.time_groups[l], uint32_t(J)), 1, stride);
  optimise_level(frame_u, grids, scale, options_.interval_iterations, step, uint32_t(J), 1, stride);
  // The contrast reported counts every event, against zero flow on every event.
  const std::vector<float> full = normalisation(frame_u, options_.tiles.back(), 1, 1);
  const ContrastEval final_eval = evaluate(frame_u, grids, full, false);
  ExposureFlow out;
  out.width = events.width;
  out.height = events.height;
  out.frame_u = frame_u;
  out.contrast = 0;
  for (uint32_t r = 0; r < kFlowRefs; ++r) out.contrast += full[r] == 0 ? kRefWeight[r] : -full[r] * final_eval.g[r];
  for (size_t j = 0; j < J; ++j) {
    IntervalFlow f;
    f.grid = grids[j];
    for (uint32_t c : event_counts(events, frame_u[j], frame_u[j + 1])) f.events += c;
    out.intervals.push_back(std::move(f));
  }
  return out;
}

}  // namespace evflow::flow
