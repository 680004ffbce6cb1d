#include "train/gaussian_optimizer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "optim/schedule.h"

namespace evflow {

double scene_extent(const io::Dataset& data) {
  double mean[3] = {0, 0, 0};
  for (auto& v : data.train) {
    auto c = v.camera.center();
    for (int i = 0; i < 3; ++i) mean[i] += c[i] / data.train.size();
  }
  double r = 0;
  for (auto& v : data.train) {
    auto c = v.camera.center();
    r = std::max(r, std::sqrt((c[0] - mean[0]) * (c[0] - mean[0]) + (c[1] - mean[1]) * (c[1] - mean[1]) +
                              (c[2] - mean[2]) * (c[2] - mean[2])));
  }
  return std::max(1.0, 1.1 * r);
}

static DensityConfig density_config(const TrainConfig& cfg) {
  DensityConfig d;
  d.refine_from = cfg.densify_from;
  d.refine_until = cfg.densify_until;
  d.refine_every = cfg.densify_every;
  d.grad_threshold = float(cfg.densify_grad_threshold);
  d.max_screen_radius = float(cfg.prune_screen_px);
  d.max_world_scale = float(cfg.prune_world_scale);
  d.reset_every = cfg.opacity_reset_every;
  d.max_gaussians = cfg.max_gaussians;
  d.seed = uint32_t(cfg.seed);
  return d;
}

GaussianOptimizer::GaussianOptimizer(gpu::Context& ctx, gpu::Commands& cmd, GaussianBuffers& params,
                                     GaussianBuffers& grads, const TrainConfig& cfg, double extent)
    : params_(params),
      grads_(grads),
      extent_(extent),
      lr_means_init_(cfg.lr_means_init),
      lr_means_final_(cfg.lr_means_final),
      iterations_(cfg.iterations),
      adam_(std::make_unique<Adam>(ctx)) {
  add_groups(cfg);
  if (cfg.densify) {
    stats_ = std::make_unique<DensityStats>(ctx);
    density_ = std::make_unique<DensityControl>(ctx, density_config(cfg));
    stats_->reset(cmd, uint32_t(params.count));
    cmd.submit();
  }
}

void GaussianOptimizer::add_groups(const TrainConfig& cfg) {
  const uint32_t n = uint32_t(params_.count);
  GaussianBuffers &p = params_, &g = grads_;
  means_group_ = adam_->add_group({"means", &p.means, &g.means, n * 3, float(cfg.lr_means_init * extent_), 3});
  adam_->add_group({"log_scales", &p.log_scales, &g.log_scales, n * 3, float(cfg.lr_log_scales), 3});
  adam_->add_group({"quats", &p.quats, &g.quats, n * 4, float(cfg.lr_quats), 4});
  adam_->add_group({"opacity_logits", &p.opacity_logits, &g.opacity_logits, n, float(cfg.lr_opacity), 1});
  sh_groups_.push_back(adam_->add_group({"sh0", &p.sh[0], &g.sh[0], n * 3, float(cfg.lr_sh_dc), 3}));
  static const uint32_t band[4] = {1, 3, 5, 7};
  for (int l = 1; l <= p.sh_degree; ++l)
    sh_groups_.push_back(adam_->add_group(
        {"sh" + std::to_string(l), &p.sh[l], &g.sh[l], n * band[l] * 3, float(cfg.lr_sh_rest), band[l] * 3}));
}

void GaussianOptimizer::step(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, const Camera& camera, uint32_t step,
                             int sh_degree) {
  const ExponentialDecay sched{lr_means_init_ * extent_, lr_means_final_ * extent_, iterations_};
  adam_->set_lr(means_group_, float(sched(step)));
  if (density_) stats_->accumulate(cmd, grad2d_norm, params_, camera, 0.5f * camera.width);
  // The bands above the active degree have a zero gradient: until they first become active their
  // update is zero too, and Adam only counts the step (at degree 0 of 3, 45 of 59 floats a Gaussian).
  for (size_t i = 0; i < adam_->group_count(); ++i) {
    const auto band = std::find(sh_groups_.begin(), sh_groups_.end(), i);
    if (band != sh_groups_.end() && int(band - sh_groups_.begin()) > sh_degree)
      adam_->step_group_zero_grad(cmd, i);
    else
      adam_->step_group(cmd, i);
  }
  cmd.submit();
  if (!density_) return;
  const DensityConfig& d = density_->config();
  if (d.refine_at(step)) density_->refine(cmd, params_, grads_, *adam_, *stats_, float(extent_), d.prune_big_at(step));
  if (d.reset_at(step)) {
    density_->reset_opacity(cmd, params_, *adam_);
    cmd.submit();
  }
}

std::vector<OptimizerGroupState> GaussianOptimizer::state() const {
  std::vector<OptimizerGroupState> out;
  for (size_t i = 0; i < adam_->group_count(); ++i) {
    const uint32_t n = adam_->group(i).count;
    const bool fresh = adam_->step_count(i) == 0;  // moments not initialised before the first step
    out.push_back({adam_->group(i).name, adam_->step_count(i),
                   fresh ? std::vector<float>(n, 0.f) : adam_->exp_avg(i).read<float>(n),
                   fresh ? std::vector<float>(n, 0.f) : adam_->exp_avg_sq(i).read<float>(n)});
  }
  return out;
}

void GaussianOptimizer::load(const std::vector<OptimizerGroupState>& saved) {
  for (auto& g : saved) adam_->load_state(adam_->group_index(g.name), g.exp_avg, g.exp_avg_sq, g.step);
}

}  // namespace evflow
