// The training loop. A step is a short pipeline of stages, each its own object:
//
//   choose the view -> render the exposure (ExposureRender: 2N+1 frames at the CameraModel's
//   poses) -> image model (ImageModel: the blurry mean) -> loss terms (LossTerms: image terms,
//   then exposure terms; DirectionCheck) -> backward through frames, trajectory and poses ->
//   optimizer and density control (GaussianOptimizer).
//
// Parameters, images and gradients stay on the GPU; per step the host reads back the loss
// values (and the intersection counts). docs/architecture.md shows where new terms plug in.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "events/gpu_events.h"
#include "io/dataset.h"
#include "loss/residual_loss.h"
#include "loss/warped_event_loss.h"
#include "splat/rasterizer.h"
#include "train/camera_model.h"
#include "train/checkpoint.h"
#include "train/direction_check.h"
#include "train/edi_warmup.h"
#include "train/exposure_render.h"
#include "train/gaussian_optimizer.h"
#include "train/image_model.h"
#include "train/ldi_branch.h"
#include "train/loss_terms.h"
#include "train/model_flow.h"
#include "train/train_config.h"
#include "train/training_data.h"

namespace evflow {

struct StepStats {
  uint32_t step = 0;
  uint32_t view = 0;
  double loss = 0;
  bool skipped = false;  // non-finite loss: the update was not applied
  bool flipped = false;  // the view's trajectory was reversed in time (events scored it better); no update this step
  double ms = 0;
  // Wall-clock split of the step (each part ends in a submit and wait); optimizer_ms includes
  // density control; ldi_ms: the LDI branch's forward, terms, backward and Adam step (ldi=on).
  double raster_forward_ms = 0, loss_ms = 0, raster_backward_ms = 0, optimizer_ms = 0, ldi_ms = 0;
  // The loss terms' stages (GPU timestamps, ms): "image model" (the frames' mean and colour
  // conversions), each term by its name, with the exposure terms "frame shares" and (while it
  // runs) "direction check", then "render gradients" (the image model's backward to each frame).
  std::vector<std::pair<std::string, double>> loss_stages;
  // The LDI branch's stages (GPU timestamps, ms; LdiBranch's marks), forward then backward.
  std::vector<std::pair<std::string, double>> ldi_stages;
  // Each term's unweighted value, in the order the terms were added (names: Trainer::losses()).
  std::vector<double> term_values;
};

// One interval's optical flow of a training view as training uses it, and what the
// warped-event loss compares there (for viewers).
struct FlowSnapshot {
  uint32_t interval = 0, intervals = 0;  // interval i of the exposure's 2N
  uint32_t width = 0, height = 0;
  std::vector<float> flow;  // d_i: H * W * 2, u and v interleaved (NaN: no flow at that pixel)
  bool warped = false;      // the warped-event loss is on and `measured` / `predicted` are set
  // M_i (the interval's events warped to t_{i+1}, signed, threshold-weighted) and P_i = -(grad
  // L_{i+1} . d_i) of the current render, H * W each, 0 off the interior (loss/warped_event_loss.h).
  std::vector<float> measured, predicted;
};

// What the residual loss L_res compares for a training view (res_weight > 0), per non-middle
// virtual frame i in frame order, planar linear RGB (3 x H x W each).
struct ResidualSnapshot {
  std::vector<uint32_t> frames;             // the frames' indices i (the middle one, N, left out)
  std::vector<std::vector<float>> prior;    // the residual prior's R(t_i), as the loss holds it
  std::vector<std::vector<float>> renders;  // the renders' F_i - F_N in linear light
};

// Training view v as the model sees it between steps (for viewers).
struct ViewSnapshot {
  std::vector<double> times;  // the frames' exposure times u
  std::vector<const gpu::Buffer*>
      frames;                 // their renders, planar sRGB on the GPU (valid until the next step or snapshot)
  std::vector<float> model;   // the image model's prediction (blur: the frames' mean), planar sRGB
  std::vector<float> target;  // the training target, planar sRGB
  bool has_flow = false;      // snapshot(v, interval) of a run that uses flow: `flow` is set
  FlowSnapshot flow;
  // Asked for (SnapshotExtras::ldi_frames) in an ldi=on run: the LDI network's frames C_ldi(t_i)
  // at `times` over the whole view, planar linear RGB (LdiBranch::view_frames); else empty.
  std::vector<std::vector<float>> ldi_frames;
  bool has_residuals = false;  // asked for in a run with the residual loss: `residuals` is set
  ResidualSnapshot residuals;
};

// What a snapshot adds to the renders on request (each costs time: for viewers that show it).
struct SnapshotExtras {
  bool ldi_frames = false;  // ldi=on: the LDI frames over the whole view (2 (2N+1) - 2 network calls)
  bool residuals = false;   // res_weight > 0: what the residual loss compares (read back)
};

// The training view of a step: a seeded shuffle of the views per epoch (steps count from 1).
uint32_t view_for_step(uint32_t step, size_t views, uint64_t seed);

class Trainer {
 public:
  Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg);
  // Continues from a checkpoint (Gaussians, step and optimizer state: bit-identical on the same
  // device; with ldi=on the checkpoint's `ldi` state is required once past step 0).
  Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg, const Checkpoint& start);

  StepStats step();
  uint32_t current_step() const { return step_; }
  const TrainConfig& config() const { return cfg_; }
  GaussianCloud cloud() const { return params_->download(); }
  Checkpoint checkpoint() const;
  // Renders `cam` with the current Gaussians into planar sRGB (3 x H x W) on the host.
  std::vector<float> render(const Camera& cam);
  const Rasterizer& rasterizer() const { return raster_; }
  const GaussianBuffers& params() const { return *params_; }
  // Blur mode: the training views' exposure trajectories (empty in plain mode).
  const std::vector<ExposureTrajectory>& trajectories() const { return cameras_->trajectories(); }
  // The camera the model currently believes view v was taken from: mid-exposure of its
  // trajectory (blur mode), the refined pose (pose_refine) or the dataset's pose.
  Camera training_camera(uint32_t v) const { return cameras_->training_camera(v); }
  // The loss terms, in the order added. Exposure terms need the virtual frames of mode=blur.
  void add_loss(std::unique_ptr<ImageLossTerm> term) { terms_.add(std::move(term)); }
  void add_loss(std::unique_ptr<ExposureLossTerm> term);
  const std::vector<LossTerm*>& losses() const { return terms_.all(); }
  // What the last step applied, before Adam: the loss gradient of every Gaussian parameter (a
  // cloud of gradients), and that of its view's camera (54 trajectory knots in blur mode, the
  // 6-vector pose delta with pose_refine, else empty). For tests and diagnostics.
  GaussianCloud last_gradients() const { return grads_->download(); }
  const std::vector<double>& last_camera_gradient() const { return cameras_->last_gradient(); }
  uint32_t trajectory_flips() const { return flips_; }
  // Renders view v's exposure as the next step would (its render settings) without training;
  // with interval >= 0 and a run that uses flow, also that interval's flow and warped events;
  // and the extras asked for that the run has.
  ViewSnapshot snapshot(uint32_t v, int interval = -1, SnapshotExtras extras = {});
  // The flow's intervals per exposure (2N) when the run uses flow (warp_weight, blur_upsample), else 0.
  uint32_t flow_intervals() const { return flows_.empty() ? 0 : uint32_t(flows_[0].size()); }
  // The step at which the model's flow was last computed (flow=model, flow_model_from); 0: never.
  uint32_t model_flow_step() const { return model_flow_step_; }
  // The learnable double integral branch (ldi=on), else null.
  LdiBranch* ldi() { return ldi_.get(); }

 private:
  void setup(const Checkpoint& start);
  void add_ldi_branch(const Checkpoint& start);
  void upload_targets();
  void add_event_term();
  void add_residual_term();
  void setup_flows();
  void add_warp_term();
  void set_image_model(uint32_t upsample);
  uint32_t upsample_at(uint32_t step) const;
  uint32_t model_flow_start() const;
  bool model_flow_due(bool exposure_on) const;
  void refresh_model_flows();
  void refresh_model_flow(uint32_t v);
  void upload_view_flow(uint32_t v);
  FlowSnapshot flow_snapshot(uint32_t v, uint32_t interval);
  ResidualSnapshot residual_snapshot(uint32_t v) const;
  RenderSettings render_settings() const;
  // A step of the EDI warm-up: one render, its image terms, its backward (edi_warmup).
  void warmup_step(StepStats& st);
  // The stages of a step.
  void render_exposure(uint32_t view);
  void record_losses(StepStats& st, bool exposure_on);
  std::vector<const gpu::Buffer*> record_exposure_terms(const StepStats& st, bool check);
  void read_losses(StepStats& st, bool exposure_on, bool branches_on) const;
  double event_schedule() const;
  // From every frame's render gradient (record_losses; the LDI branch adds the joint loss's
  // share) through the rasterizer to the Gaussians and the frames' poses.
  void backward_raster(uint32_t view);

  gpu::Context& ctx_;
  const io::Dataset& data_;
  TrainConfig cfg_;
  Rasterizer raster_;
  gpu::Commands cmd_;
  std::unique_ptr<GaussianBuffers> params_, grads_;
  std::vector<gpu::Buffer> targets_;  // per view, in loss_space
  gpu::Buffer v_alpha_;
  std::unique_ptr<CameraModel> cameras_;
  std::unique_ptr<ExposureRender> exposure_;
  std::unique_ptr<ImageModel> image_model_;
  LossTerms terms_;
  std::unique_ptr<IntervalEvents> events_;  // training views' events (when a term needs them)
  std::unique_ptr<DirectionCheck> direction_;
  std::vector<gpu::Buffer> frame_grad_;   // per virtual frame, linear light (exposure terms only)
  std::vector<gpu::Buffer> flow_planes_;  // per view, the upsampled blur's displacement planes
  // Per view, per interval: the flow in use, H * W * 2 (NaN: none); empty when no term uses flow.
  std::vector<std::vector<std::vector<float>>> flows_;
  WarpedEventLoss* warp_ = nullptr;        // the warped-event term, when on
  ResidualLoss* residual_ = nullptr;       // the residual term, when on
  std::unique_ptr<ModelFlow> model_flow_;  // flow=model or flow_model_from
  uint32_t model_flow_step_ = 0;
  std::unique_ptr<GaussianOptimizer> optimizer_;
  std::unique_ptr<LdiBranch> ldi_;     // ldi=on
  std::unique_ptr<EdiWarmup> warmup_;  // edi_warmup > 0
  RenderState preview_;                // render()
  uint32_t step_ = 0;
  uint32_t flips_ = 0;
};

}  // namespace evflow
