#include "densify/density_control.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "densify/densify_layout.h"
#include "splat/camera_pc.h"

namespace evflow {

using namespace shaderio;
static_assert(kDensifyNoSource == kAdamNoSource);

namespace {

constexpr uint32_t kBandCoeffs[4] = {1, 3, 5, 7};

gpu::Groups groups_for(const gpu::Commands& cmd, uint64_t n) {
  return cmd.linear_groups(gpu::Commands::div_up(n, kDensifyGroupSize));
}

uint64_t words(uint64_t n) { return std::max<uint64_t>(n * 4, 16); }

float logit(double p) { return static_cast<float>(std::log(p / (1.0 - p))); }

// The name prefix of a GaussianBuffers ("p_" for "p_means"), to name the fresh buffers alike.
std::string prefix_of(const GaussianBuffers& b) {
  const std::string& n = b.means.name();
  return n.size() >= 5 && n.compare(n.size() - 5, 5, "means") == 0 ? n.substr(0, n.size() - 5) : n + "_";
}

}  // namespace

// ------------------------------------------------------------------------------ statistics

DensityStats::DensityStats(gpu::Context& ctx)
    : ctx_(ctx),
      grad_sum_(ctx, 16, "densify_grad_sum"),
      vis_count_(ctx, 16, "densify_vis_count"),
      max_radius_(ctx, 16, "densify_max_radius") {}

void DensityStats::reset(gpu::Commands& cmd, uint32_t count) {
  // ensure() may reallocate: callers submit before a reset that changes the count (refine does).
  grad_sum_.ensure(words(count));
  vis_count_.ensure(words(count));
  max_radius_.ensure(words(count));
  count_ = count;
  cmd.fill(grad_sum_, 0u);
  cmd.fill(vis_count_, 0u);
  cmd.fill(max_radius_, 0u);  // 0.0f
}

void DensityStats::accumulate(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, float grad_scale) {
  if (!count_) return;
  if (grad2d_norm.size() < uint64_t(count_) * 4)
    throw std::invalid_argument("DensityStats: grad2d_norm smaller than the count");
  AccumulatePC pc{};
  pc.count = count_;
  pc.use_camera = 0;
  pc.grad_scale = grad_scale;
  // Parameter bindings are unused without a camera: bind the statistics buffers in their place.
  cmd.dispatch("densify/accumulate",
               {{kDensifyAccumulateBindGrad2d, grad2d_norm},
                {kDensifyAccumulateBindMeans, grad_sum_},
                {kDensifyAccumulateBindLogScales, grad_sum_},
                {kDensifyAccumulateBindQuats, grad_sum_},
                {kDensifyAccumulateBindGradSum, grad_sum_},
                {kDensifyAccumulateBindVisCount, vis_count_},
                {kDensifyAccumulateBindMaxRadius, max_radius_}},
               pc, groups_for(cmd, count_));
}

void DensityStats::accumulate(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, const GaussianBuffers& params,
                              const Camera& cam, float grad_scale) {
  if (!count_) return;
  if (params.count != count_)
    throw std::invalid_argument("DensityStats: parameter count differs from the statistics' count");
  if (grad2d_norm.size() < uint64_t(count_) * 4)
    throw std::invalid_argument("DensityStats: grad2d_norm smaller than the count");
  AccumulatePC pc{};
  pc.cam = camera_pc(cam);
  pc.count = count_;
  pc.use_camera = 1;
  pc.grad_scale = grad_scale;
  cmd.dispatch("densify/accumulate",
               {{kDensifyAccumulateBindGrad2d, grad2d_norm},
                {kDensifyAccumulateBindMeans, params.means},
                {kDensifyAccumulateBindLogScales, params.log_scales},
                {kDensifyAccumulateBindQuats, params.quats},
                {kDensifyAccumulateBindGradSum, grad_sum_},
                {kDensifyAccumulateBindVisCount, vis_count_},
                {kDensifyAccumulateBindMaxRadius, max_radius_}},
               pc, groups_for(cmd, count_));
}

// ------------------------------------------------------------------------------ refinement

DensityControl::DensityControl(gpu::Context& ctx, DensityConfig cfg)
    : ctx_(ctx),
      cfg_(cfg),
      scan_(ctx),
      sort_(ctx),
      decision_(ctx, 16, "densify_decision"),
      out_count_(ctx, 16, "densify_out_count"),
      offsets_(ctx, 16, "densify_offsets"),
      base_offsets_(ctx, 16, "densify_base_offsets"),
      keys_(ctx, 16, "densify_keys"),
      ids_(ctx, 16, "densify_ids"),
      sorted_extra_(ctx, 16, "densify_sorted_extra"),
      extra_offsets_(ctx, 16, "densify_extra_offsets"),
      param_src_(ctx, 16, "densify_param_src"),
      state_src_(ctx, 16, "densify_state_src"),
      row_code_(ctx, 16, "densify_row_code"),
      mask_(ctx, 16, "densify_mask") {}

RefineResult DensityControl::refine(gpu::Commands& cmd, GaussianBuffers& params, GaussianBuffers& grads, Adam& adam,
                                    DensityStats& stats, float extent, bool prune_big) {
  const uint64_t n64 = params.count;
  if (n64 > 0x7FFFFFFFull) throw std::invalid_argument("DensityControl: too many Gaussians");
  const uint32_t n = static_cast<uint32_t>(n64);
  if (stats.count() != n)
    throw std::invalid_argument("DensityControl: statistics sized for " + std::to_string(stats.count()) +
                                " Gaussians, parameters hold " + std::to_string(n));
  if (grads.count != n || grads.sh_degree != params.sh_degree)
    throw std::invalid_argument("DensityControl: gradient buffers do not match the parameters");
  RefineResult res{n, n};
  if (n == 0) return res;
  const float log_div = static_cast<float>(std::log(double(cfg_.split_divisor)));
  // Growth can at most double the count; with a cap below that, sort the candidates.
  const bool capped = cfg_.max_gaussians > 0 && uint64_t(n) * 2 > cfg_.max_gaussians;

  // ---- phase 1: decide, (cap), scan, read back the new count.
  // All ensure() calls happen before recording: the buffers were last used by submitted work.
  decision_.ensure(words(n));
  out_count_.ensure(words(n));
  offsets_.ensure(words(uint64_t(n) + 1));
  if (capped) {
    keys_.ensure(words(n));
    ids_.ensure(words(n));
    base_offsets_.ensure(words(uint64_t(n) + 1));
    sorted_extra_.ensure(words(n));
    extra_offsets_.ensure(words(n));
  }
  DecidePC dpc{};
  dpc.count = n;
  dpc.grad_threshold = cfg_.grad_threshold;
  dpc.clone_max_scale = cfg_.percent_dense * extent;
  dpc.min_opacity_logit = logit(cfg_.min_opacity);
  // 0 turns a rule off.
  dpc.max_screen_radius = cfg_.max_screen_radius > 0 ? cfg_.max_screen_radius : std::numeric_limits<float>::infinity();
  dpc.max_world_scale =
      cfg_.max_world_scale > 0 ? cfg_.max_world_scale * extent : std::numeric_limits<float>::infinity();
  dpc.log_split_div = log_div;
  dpc.prune_big = prune_big ? 1u : 0u;
  dpc.capped = capped ? 1u : 0u;
  // Without the cap the key/id bindings are not written: bind scratch buffers in their place.
  const gpu::Buffer& keys = capped ? keys_ : offsets_;
  const gpu::Buffer& ids = capped ? ids_ : offsets_;
  cmd.dispatch("densify/decide",
               {{kDecideBindLogScales, params.log_scales},
                {kDecideBindOpacity, params.opacity_logits},
                {kDecideBindGradSum, stats.grad_sum()},
                {kDecideBindVisCount, stats.vis_count()},
                {kDecideBindMaxRadius, stats.max_radius()},
                {kDecideBindDecision, decision_},
                {kDecideBindOutCount, out_count_},
                {kDecideBindKeys, keys},
                {kDecideBindIds, ids}},
               dpc, groups_for(cmd, n));
  if (capped) {
    scan_.record(cmd, out_count_, base_offsets_, n, n + 1);  // base_offsets_[n]: rows without growth
    auto sorted = sort_.record(cmd, keys_, ids_, n, 32);
    CapPC cpc{n, cfg_.max_gaussians, 0, 0};
    cmd.dispatch(
        "densify/cap_extra",
        {{kCapExtraBindIds, *sorted.second}, {kCapExtraBindDecision, decision_}, {kCapExtraBindExtra, sorted_extra_}},
        cpc, groups_for(cmd, n));
    scan_.record(cmd, sorted_extra_, extra_offsets_, n, n);
    cmd.dispatch("densify/cap_grant",
                 {{kCapGrantBindIds, *sorted.second},
                  {kCapGrantBindExtra, sorted_extra_},
                  {kCapGrantBindExtraScan, extra_offsets_},
                  {kCapGrantBindBaseScan, base_offsets_},
                  {kCapGrantBindDecision, decision_},
                  {kCapGrantBindOutCount, out_count_}},
                 cpc, groups_for(cmd, n));
  }
  scan_.record(cmd, out_count_, offsets_, n, n + 1);
  cmd.submit();
  const uint32_t m = offsets_.read_one<uint32_t>(n);  // the one readback
  res.after = m;
  if (m > GaussianBuffers::max_count(ctx_, params.sh_degree))
    throw gpu::Error("DensityControl: " + std::to_string(m) +
                     " Gaussians exceed the device's binding limit; set a cap");

  // ---- phase 2: index, gather everything into fresh buffers, move the optimizer state.
  param_src_.ensure(words(m));
  state_src_.ensure(words(m));
  row_code_.ensure(words(m));
  GaussianBuffers new_params(ctx_, m, params.sh_degree, prefix_of(params));
  GaussianBuffers new_grads(ctx_, m, grads.sh_degree, prefix_of(grads));
  EmitPC epc{};
  epc.count = n;
  epc.rows = m;
  epc.seed = cfg_.seed * 0x9E3779B9u + refinements_ * 0x85EBCA6Bu + 0x1234567u;
  epc.log_split_div = log_div;
  epc.max_sigma = cfg_.split_max_sigma;
  cmd.dispatch("densify/index",
               {{kDensifyIndexBindDecision, decision_},
                {kDensifyIndexBindOffsets, offsets_},
                {kDensifyIndexBindParamSrc, param_src_},
                {kDensifyIndexBindStateSrc, state_src_},
                {kDensifyIndexBindCode, row_code_}},
               epc, groups_for(cmd, n));
  if (m > 0) {
    cmd.dispatch("densify/geometry",
                 {{kDensifyGeometryBindMeans, params.means},
                  {kDensifyGeometryBindLogScales, params.log_scales},
                  {kDensifyGeometryBindQuats, params.quats},
                  {kDensifyGeometryBindParamSrc, param_src_},
                  {kDensifyGeometryBindCode, row_code_},
                  {kDensifyGeometryBindNewMeans, new_params.means},
                  {kDensifyGeometryBindNewLogScales, new_params.log_scales}},
                 epc, groups_for(cmd, m));
    Adam::gather_rows(cmd, params.quats, new_params.quats, param_src_, m, 4);
    Adam::gather_rows(cmd, params.opacity_logits, new_params.opacity_logits, param_src_, m, 1);
    for (int l = 0; l <= params.sh_degree; ++l)
      Adam::gather_rows(cmd, params.sh[l], new_params.sh[l], param_src_, m, kBandCoeffs[l] * 3);
  }
  for (gpu::Buffer* b : {&new_grads.means, &new_grads.log_scales, &new_grads.quats, &new_grads.opacity_logits,
                         &new_grads.sh[0], &new_grads.sh[1], &new_grads.sh[2], &new_grads.sh[3]})
    cmd.fill(*b, 0u);
  // Adam groups of the Gaussians, by name.
  std::vector<std::pair<size_t, int>> moved;  // group index, field (0..3 geometry, 4 + l SH band)
  static const char* kNames[8] = {"means", "log_scales", "quats", "opacity_logits", "sh0", "sh1", "sh2", "sh3"};
  for (size_t i = 0; i < adam.group_count(); ++i)
    for (int f = 0; f < 8; ++f)
      if (adam.group(i).name == kNames[f] && (f < 4 || f - 4 <= params.sh_degree)) {
        adam.gather(cmd, i, state_src_, m);
        moved.emplace_back(i, f);
      }
  // Statistics restart from zero (ensure() on buffers only referenced by submitted work).
  stats.reset(cmd, m);
  cmd.submit();

  params = std::move(new_params);
  grads = std::move(new_grads);
  for (auto [i, f] : moved) {
    auto field = [&](GaussianBuffers& b) -> const gpu::Buffer& {
      switch (f) {
        case 0:
          return b.means;
        case 1:
          return b.log_scales;
        case 2:
          return b.quats;
        case 3:
          return b.opacity_logits;
        default:
          return b.sh[f - 4];
      }
    };
    adam.set_buffers(i, field(params), field(grads));
  }
  ++refinements_;
  return res;
}

void DensityControl::reset_opacity(gpu::Commands& cmd, GaussianBuffers& params, Adam& adam) {
  const uint32_t n = static_cast<uint32_t>(params.count);
  if (n == 0) return;
  mask_.ensure(words(n));
  ResetPC pc{n, logit(cfg_.reset_opacity), 0, 0};
  cmd.dispatch("densify/opacity_reset",
               {{kOpacityResetBindOpacity, params.opacity_logits}, {kOpacityResetBindMask, mask_}}, pc,
               groups_for(cmd, n));
  for (size_t i = 0; i < adam.group_count(); ++i)
    if (adam.group(i).name == "opacity_logits") adam.reset_masked(cmd, i, mask_);
}

}  // namespace evflow
