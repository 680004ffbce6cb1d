// The training loop: per step one view, render, loss terms (a registry: each adds its weighted
// gradient into one image gradient), backward, Adam. Parameters, images and gradients stay on
// the GPU; per step the host reads back the loss value (and the intersection count).
#pragma once
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "camera/trajectory.h"
#include "densify/density_control.h"
#include "io/dataset.h"
#include "loss/loss_term.h"
#include "optim/adam.h"
#include "splat/rasterizer.h"
#include "train/checkpoint.h"
#include "train/train_config.h"

namespace evflow {

struct StepStats {
  uint32_t step = 0;
  uint32_t view = 0;
  double loss = 0;
  bool skipped = false;  // non-finite loss: the update was not applied
  double ms = 0;
  // Wall-clock split of the step (each part ends in a submit and wait).
  double raster_forward_ms = 0, loss_ms = 0, raster_backward_ms = 0, optimizer_ms = 0;
};

// Random Gaussians inside the training views' frustums between the near and far bounds, coloured
// from the pixel they were seeded on.
GaussianCloud initial_cloud(const io::Dataset& data, const TrainConfig& cfg);

class Trainer {
 public:
  Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg);
  // Continues from a checkpoint (Gaussians, step and optimizer state: bit-identical on the same device).
  Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg, const Checkpoint& start);

  StepStats step();
  uint32_t current_step() const { return step_; }
  const TrainConfig& config() const { return cfg_; }
  GaussianCloud cloud() const { return params_->download(); }
  Checkpoint checkpoint() const;
  // Renders `cam` with the current Gaussians into planar RGB (3 x H x W) on the host.
  std::vector<float> render(const Camera& cam);
  Rasterizer& rasterizer() { return raster_; }
  const GaussianBuffers& params() const { return *params_; }
  // Blur mode: the training views' exposure trajectories (empty in plain mode).
  const std::vector<ExposureTrajectory>& trajectories() const { return trajectories_; }
  // The loss-term registry.
  void add_loss(std::unique_ptr<LossTerm> term) { terms_.push_back(std::move(term)); }
  const std::vector<std::unique_ptr<LossTerm>>& losses() const { return terms_; }

 private:
  void setup(const GaussianCloud& start);
  double blur_step(const io::View& view, uint32_t v, const RenderSettings& s, StepStats& st);
  void trajectory_adam(uint32_t v, const std::array<double, ExposureTrajectory::kSize>& grad);
  gpu::Context& ctx_;
  const io::Dataset& data_;
  TrainConfig cfg_;
  Rasterizer raster_;
  gpu::Commands cmd_;
  std::unique_ptr<GaussianBuffers> params_, grads_;
  std::vector<gpu::Buffer> targets_;
  gpu::Buffer v_rgb_, v_alpha_;
  std::vector<std::unique_ptr<LossTerm>> terms_;
  std::unique_ptr<Adam> adam_;
  std::unique_ptr<DensityStats> density_stats_;
  std::unique_ptr<DensityControl> density_;
  std::vector<ExposureTrajectory> trajectories_;
  std::vector<TrajectoryState> trajectory_state_;  // Adam moments per view (knots live in trajectories_)
  gpu::Buffer mean_image_;
  size_t means_group_ = 0;
  double extent_ = 1.0;
  uint32_t step_ = 0;
};

}  // namespace evflow
