// Training configuration: every option with its default, set from a JSON file, a preset and
// key=value overrides (in that order).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "camera/trajectory.h"

namespace evflow {

// The values of the keys loss_space, mode, target and init (their settings-table entries say what
// each value does); the name functions give the keys' text.
enum class LossSpace { Linear, Srgb };
const char* loss_space_name(LossSpace s);
enum class TrainMode { Plain, Blur };
const char* mode_name(TrainMode m);
enum class TrainTarget { Blurry, Sharp, Edi };
const char* target_name(TrainTarget t);
enum class FlowSource { Events, Gt, Model };
const char* flow_source_name(FlowSource f);
enum class InitSource { Random, Points };
const char* init_name(InitSource s);

// One setting as `evflow train --keys` and docs/training.md show it.
struct SettingDoc {
  std::string group;  // the settings table it belongs to
  std::string key;
  std::string value;  // the default, and the paper preset's value where that differs
  std::string doc;    // what it means
};

// The members' meanings, their parsing and their JSON form are the settings tables in
// train_config.cpp (one entry per key); the defaults are the member initialisers below.
struct TrainConfig {
  std::string preset = "fast";
  uint32_t iterations = 1500;
  InitSource init = InitSource::Random;
  uint32_t init_gaussians = 20000;
  int sh_degree = 3;
  uint32_t sh_increase_every = 500;
  double lr_means_init = 1.6e-4, lr_means_final = 1.6e-6;
  double lr_sh_dc = 2.5e-3, lr_sh_rest = 2.5e-3 / 20, lr_opacity = 0.05, lr_log_scales = 5e-3, lr_quats = 1e-3;
  double ssim_lambda = 0.2;
  LossSpace loss_space = LossSpace::Srgb;
  TrainMode mode = TrainMode::Plain;
  uint32_t virtual_frames = 3;
  uint32_t blur_upsample = 1;
  double upsample_from = 0.0;  // fraction of the blur steps before the upsampled blur starts
  double edi_warmup = 0.0;
  double edi_warmup_motion = 0.0;
  double splats_from = 0.0;
  bool edi_keep_mid = false;
  double edi_mid_lr = 0.0;
  double lr_trajectory_init = 6e-3, lr_trajectory_final = 6e-4;
  double trajectory_init_sigma = ExposureTrajectory::kDefaultInitSigma;
  double event_weight = 0.0;
  double event_theta_pos = 0.0, event_theta_neg = 0.0;
  double event_norm_floor = 1e-3;
  uint32_t event_pool = 1;
  double event_weight_end = 0.0;
  double event_flip_until = 0.8, event_flip_margin = 0.05;
  double event_from = 0.3;
  double warp_weight = 0.0;
  double res_weight = 0.0;
  std::string res_prior = "assets/residual_prior.safetensors";
  FlowSource flow = FlowSource::Events;
  uint32_t flow_refresh = 100;
  double flow_model_from = 0.0;
  bool pose_refine = false;
  double lr_pose_init = 1e-3, lr_pose_final = 1e-5;
  TrainTarget target = TrainTarget::Blurry;
  bool antialiased = false;
  std::array<float, 3> background{0, 0, 0};
  uint64_t seed = 0;
  uint32_t log_every = 100;
  uint32_t checkpoint_every = 1000;
  bool densify = true;
  uint32_t densify_from = 500, densify_until = 15000, densify_every = 100;
  double densify_grad_threshold = 2e-4;
  double prune_screen_px = 0, prune_world_scale = 0;
  uint32_t opacity_reset_every = 3000;
  uint32_t max_gaussians = 30000;
  bool ldi = false;
  std::vector<uint32_t> ldi_widths{32, 16, 16, 1};
  uint32_t ldi_crop = 48;
  double ldi_blur_weight = 1.0, ldi_event_weight = 0.1, joint_weight = 1.0;
  double joint_from = 0.0;
  double joint_ldi_share = 1.0;
  double ldi_anchor_weight = 1.0;
  double ldi_lr = 1e-3;
  uint32_t ldi_init_steps = 300;
  double ldi_init_lr = 3e-3;

  static TrainConfig preset_named(const std::string& name);  // "fast" (CPU) or "paper" (GPU)
  // The paper's configurations and baselines (key "method"): plain (3DGS on the blurry images),
  // edi (3DGS on EDI-deblurred images), blur-only (BAD-Gaussians-like: mode=blur), blur+events
  // (mode=blur + the event loss, lambda 0.1), blur+events+warp (+ the warped-event loss, lambda 0.1), blur+events+flow
  // (+ the flow-upsampled blur, M = 4), blur+res (blur + the residual loss), blur+events+warp+res,
  // evflow-no-ldi-events (+ the LDI branch without its event loss), evflow (the full model).
  void apply_method(const std::string& name);
  // The last step of the EDI warm-up (edi_warmup of the run's steps; 0: none).
  uint32_t edi_warmup_steps() const { return uint32_t(edi_warmup * iterations); }
  // The last warm-up step that fits the virtual frames (edi_warmup_motion; 0: none).
  uint32_t edi_motion_steps() const { return uint32_t(edi_warmup_motion * edi_warmup_steps()); }
  // Where a fraction of the blur steps ends (event_from, event_flip_until, flow_model_from,
  // joint_from, upsample_from): the
  // blur steps after an EDI warm-up keep the schedule a run of that many steps would have.
  double blur_point(double fraction) const {
    const uint32_t w = edi_warmup_steps();
    return w + fraction * (iterations - w);
  }
  uint32_t blur_step(double fraction) const { return uint32_t(blur_point(fraction)); }
  static std::vector<std::string> methods();
  void set(const std::string& key, const std::string& value);  // throws naming the key and what it expects
  // "preset" first, then "method", then every other key (so explicit keys win).
  void apply_json(const nlohmann::json& j);
  nlohmann::json to_json() const;          // every key but "method" (which only sets others)
  static std::vector<std::string> keys();  // in the tables' order
  static std::vector<SettingDoc> describe();
  // describe() as markdown, one table per group: `evflow train --keys` prints it and
  // docs/training.md holds it verbatim.
  static std::string describe_markdown();
};

// Throws "KEY must be in [0, 1], got V" (with one_allowed false: [0, 1)) unless value lies there
// (a NaN does not).
void require_fraction(const char* key, double value, bool one_allowed = true);

}  // namespace evflow
