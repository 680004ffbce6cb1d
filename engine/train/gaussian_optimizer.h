// The Gaussians' optimizer stage of a training step: the means' learning-rate schedule, Adam
// over every parameter group on the GPU, and adaptive density control (its screen-gradient
// statistics of each step, refinement and opacity resets when due).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "densify/density_control.h"
#include "io/dataset.h"
#include "optim/adam.h"
#include "train/checkpoint.h"
#include "train/train_config.h"

namespace evflow {

// Radius of the training cameras' centres around their mean (as 3DGS), times 1.1, at least 1.
double scene_extent(const io::Dataset& data);

class GaussianOptimizer {
 public:
  // params and grads must outlive the optimizer (density control reallocates them in place).
  GaussianOptimizer(gpu::Context& ctx, gpu::Commands& cmd, GaussianBuffers& params, GaussianBuffers& grads,
                    const TrainConfig& cfg, double extent);
  // One step after the backward pass: grad2d_norm holds the step's screen-gradient norms,
  // `camera` is the view's (recorded) camera, `sh_degree` the active SH degree of the step's
  // renders (their gradient is zero in every band above it). Ends with a submit.
  void step(gpu::Commands& cmd, const gpu::Buffer& grad2d_norm, const Camera& camera, uint32_t step, int sh_degree);

  std::vector<OptimizerGroupState> state() const;
  void load(const std::vector<OptimizerGroupState>& saved);

 private:
  void add_groups(const TrainConfig& cfg);
  GaussianBuffers& params_;
  GaussianBuffers& grads_;
  double extent_;
  double lr_means_init_, lr_means_final_;
  uint32_t iterations_;
  std::unique_ptr<Adam> adam_;
  size_t means_group_ = 0;
  std::vector<size_t> sh_groups_;  // Adam's group of each SH band, band 0 first
  std::unique_ptr<DensityStats> stats_;
  std::unique_ptr<DensityControl> density_;
};

}  // namespace evflow
