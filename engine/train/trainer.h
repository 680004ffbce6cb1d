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
#include "events/gpu_events.h"
#include "io/dataset.h"
#include "loss/loss_term.h"
#include "optim/adam.h"
#include "splat/rasterizer.h"
#include "train/checkpoint.h"
#include "train/image_model.h"
#include "train/train_config.h"

namespace evflow {

struct StepStats {
  uint32_t step = 0;
  uint32_t view = 0;
  double loss = 0;
  bool skipped = false;  // non-finite loss: the update was not applied
  bool flipped = false;  // the view's trajectory was reversed in time (events scored it better); no update this step
  double ms = 0;
  // Wall-clock split of the step (each part ends in a submit and wait).
  double raster_forward_ms = 0, loss_ms = 0, raster_backward_ms = 0, optimizer_ms = 0;
  // Each registered term's unweighted value, in registry order (names: Trainer::losses()).
  std::vector<double> term_values;
};

// The image a training view is fitted to: its blurry input, its sharp ground truth, or the EDI
// estimate at mid-exposure (cfg.target). EDI needs the dataset's events.
io::Image training_target(const io::Dataset& data, size_t view, const TrainConfig& cfg);
// Event thresholds for the event loss / EDI: the config's, else the dataset's (simulator
// manifest), else 0.2.
std::pair<double, double> event_thresholds(const io::Dataset& data, const TrainConfig& cfg);

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
  // The camera the model currently believes view v was taken from: mid-exposure of its
  // trajectory (blur mode), the refined pose (pose_refine) or the dataset's pose.
  Camera training_camera(uint32_t v) const;
  // The loss-term registry.
  // Image terms compare the image model with the target; exposure terms see every virtual frame.
  void add_loss(std::unique_ptr<LossTerm> term);
  const std::vector<std::unique_ptr<LossTerm>>& losses() const { return terms_; }
  // What the last step applied, before Adam: the loss gradient of every Gaussian parameter (a
  // cloud of gradients), and that of its view's camera (54 trajectory knots in blur mode, the
  // 6-vector pose delta with pose_refine, else empty). For tests and diagnostics.
  GaussianCloud last_gradients() const { return grads_->download(); }
  const std::vector<double>& last_camera_gradient() const { return last_camera_grad_; }

 private:
  void setup(const GaussianCloud& start);
  // Virtual frame i's render state: frame 0 is raster_, the others are held so the backward
  // pass does not render them again (blur mode).
  Rasterizer& frame_raster(uint32_t i);
  void camera_adam(uint32_t v, const double* grad, double lr_init, double lr_final);
  void flip_trajectory(uint32_t v);
  gpu::Context& ctx_;
  const io::Dataset& data_;
  TrainConfig cfg_;
  Rasterizer raster_;
  gpu::Commands cmd_;
  std::unique_ptr<GaussianBuffers> params_, grads_;
  std::vector<gpu::Buffer> targets_;
  gpu::Buffer v_alpha_;
  std::vector<std::unique_ptr<LossTerm>> terms_;
  std::unique_ptr<Adam> adam_;
  std::unique_ptr<DensityStats> density_stats_;
  std::unique_ptr<DensityControl> density_;
  std::vector<ExposureTrajectory> trajectories_;
  std::vector<TrajectoryState> trajectory_state_;  // Adam moments per view (knots live in trajectories_)
  std::vector<lie::Vec6> pose_deltas_;              // plain mode with pose_refine: c2w' = c2w Exp(delta)
  std::unique_ptr<ImageModel> image_model_;
  std::unique_ptr<GpuEvents> events_;               // training views' events (when a term needs them)
  std::vector<std::unique_ptr<Rasterizer>> frame_raster_;  // virtual frames 1..2N (blur mode)
  std::vector<gpu::Buffer> frame_grad_;             // per virtual frame, linear light (exposure terms only)
  size_t means_group_ = 0;
  double extent_ = 1.0;
  uint32_t step_ = 0;
  uint32_t flips_ = 0;
  std::vector<double> last_camera_grad_;
 public:
  uint32_t trajectory_flips() const { return flips_; }
};

}  // namespace evflow
