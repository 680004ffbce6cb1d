#include "train/train_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace evflow {

namespace {

// Parsing of a key's text value; each error names the key and what it expects.
double to_double(const std::string& k, const std::string& v) {
  try {
    size_t p;
    double d = std::stod(v, &p);
    if (p != v.size() || !std::isfinite(d)) throw 1;
    return d;
  } catch (...) { throw std::invalid_argument("config key '" + k + "' expects a finite number, got '" + v + "'"); }
}
uint64_t to_uint(const std::string& k, const std::string& v) {
  try {
    size_t p;
    long long d = std::stoll(v, &p);
    if (p != v.size() || d < 0) throw 1;
    return uint64_t(d);
  } catch (...) {
    throw std::invalid_argument("config key '" + k + "' expects a non-negative integer, got '" + v + "'");
  }
}
bool to_bool(const std::string& k, const std::string& v) {
  if (v == "1" || v == "true" || v == "yes" || v == "on") return true;
  if (v == "0" || v == "false" || v == "no" || v == "off") return false;
  throw std::invalid_argument("config key '" + k + "' expects true/false, got '" + v + "'");
}
// "32,64,1": comma-separated positive integers.
std::vector<uint32_t> to_uint_list(const std::string& k, const std::string& v) {
  std::vector<uint32_t> out;
  size_t pos = 0;
  while (pos <= v.size()) {
    const size_t end = std::min(v.find(',', pos), v.size());
    const uint64_t x = to_uint(k, v.substr(pos, end - pos));
    if (x == 0 || x > 4096)
      throw std::invalid_argument("config key '" + k + "' expects widths in 1..4096, got '" + v + "'");
    out.push_back(uint32_t(x));
    pos = end + 1;
  }
  return out;
}
std::string uint_list_text(const std::vector<uint32_t>& v) {
  std::string s;
  for (uint32_t x : v) {
    if (!s.empty()) s += ',';
    s += std::to_string(x);
  }
  return s;
}

// The value of `values` whose name is v; the error lists the names.
template <typename E>
E to_enum(const std::string& k, const std::string& v, std::initializer_list<E> values, const char* (*name)(E)) {
  std::string all;
  for (E e : values) {
    if (v == name(e)) return e;
    if (!all.empty()) all += ", ";
    all += name(e);
  }
  throw std::invalid_argument("config key '" + k + "' must be one of " + all + ", got '" + v + "'");
}

// How a member type is read from a key's text and written to JSON.
template <typename T>
struct Codec;
template <>
struct Codec<double> {
  static double parse(const std::string& k, const std::string& v) { return to_double(k, v); }
};
template <>
struct Codec<uint32_t> {
  static uint32_t parse(const std::string& k, const std::string& v) { return uint32_t(to_uint(k, v)); }
};
template <>
struct Codec<uint64_t> {
  static uint64_t parse(const std::string& k, const std::string& v) { return to_uint(k, v); }
};
template <>
struct Codec<bool> {
  static bool parse(const std::string& k, const std::string& v) { return to_bool(k, v); }
};
template <>
struct Codec<std::string> {
  static std::string parse(const std::string&, const std::string& v) { return v; }
};
template <>
struct Codec<std::array<float, 3>> {
  static std::array<float, 3> parse(const std::string& k, const std::string& v) {
    float r, g, b;
    if (std::sscanf(v.c_str(), "%f,%f,%f", &r, &g, &b) != 3)
      throw std::invalid_argument("config key '" + k + "' expects r,g,b, got '" + v + "'");
    return {r, g, b};
  }
};
template <typename E, const char* (*Name)(E), E... Values>
struct EnumCodec {
  static E parse(const std::string& k, const std::string& v) { return to_enum(k, v, {Values...}, Name); }
  static nlohmann::json json(E e) { return Name(e); }
};
template <>
struct Codec<LossSpace> : EnumCodec<LossSpace, loss_space_name, LossSpace::Linear, LossSpace::Srgb> {};
template <>
struct Codec<TrainMode> : EnumCodec<TrainMode, mode_name, TrainMode::Plain, TrainMode::Blur> {};
template <>
struct Codec<FlowSource>
    : EnumCodec<FlowSource, flow_source_name, FlowSource::Events, FlowSource::Gt, FlowSource::Model> {};
template <>
struct Codec<TrainTarget>
    : EnumCodec<TrainTarget, target_name, TrainTarget::Blurry, TrainTarget::Sharp, TrainTarget::Edi> {};
template <>
struct Codec<InitSource> : EnumCodec<InitSource, init_name, InitSource::Random, InitSource::Points> {};

// Enums are written by name, everything else as its JSON number, bool or array.
template <typename T>
nlohmann::json json_of(const T& x) {
  if constexpr (std::is_enum_v<T>)
    return Codec<T>::json(x);
  else
    return x;
}

// One key: how its text sets the config, its JSON value (empty `get`: a key that only sets
// others), and what it means.
struct Setting {
  std::string key;
  std::function<void(TrainConfig&, const std::string&)> set;
  std::function<nlohmann::json(const TrainConfig&)> get;
  std::string doc;
};
struct Group {
  std::string title;
  std::vector<Setting> settings;
};

// A key stored in one member, read and written by the member type's Codec.
template <typename T>
Setting field(const char* key, T TrainConfig::*m, const char* doc) {
  return {key, [key, m](TrainConfig& c, const std::string& v) { c.*m = Codec<T>::parse(key, v); },
          [m](const TrainConfig& c) { return json_of(c.*m); }, doc};
}

// A key refused outside [lo, hi] (where a larger value is no setting but a hang, or no setting at all).
template <typename T>
Setting bounded(const char* key, T TrainConfig::*m, T lo, T hi, const char* doc) {
  return {key,
          [key, m, lo, hi](TrainConfig& c, const std::string& v) {
            const T x = Codec<T>::parse(key, v);
            if (x < lo || x > hi) {
              std::ostringstream range;
              range << lo << ".." << hi;
              throw std::invalid_argument("config key '" + std::string(key) + "' must be " + range.str() + ", got '" +
                                          v + "'");
            }
            c.*m = x;
          },
          [m](const TrainConfig& c) { return json_of(c.*m); }, doc};
}

// The settings tables: every key once, with what it means. Defaults are the member initialisers
// of TrainConfig; `evflow train --keys` prints these tables and docs/training.md holds them.

std::vector<Setting> run_settings() {
  return {
      {"preset", [](TrainConfig& c, const std::string& v) { c = TrainConfig::preset_named(v); },
       [](const TrainConfig& c) { return nlohmann::json(c.preset); },
       "`fast` (sized for CPUs) or `paper` (the paper's sizes: 40k iterations, 100k initial Gaussians); "
       "resets every other key to the preset's value, so it is applied first"},
      {"method", [](TrainConfig& c, const std::string& v) { c.apply_method(v); }, nullptr,
       "sets `mode`, `target`, `event_weight`, `warp_weight`, `blur_upsample`, `res_weight`, `ldi` and "
       "`ldi_event_weight` for one of the paper's configurations: `plain` (3DGS on the blurry images), `edi` (3DGS "
       "on EDI-deblurred images), `blur-only` (mode=blur), `blur+events` (mode=blur, event_weight 0.1), "
       "`blur+events+warp` (also warp_weight 0.1), `blur+events+flow` (also blur_upsample 4), `blur+res` (mode=blur, "
       "res_weight 0.1), `blur+events+warp+res`, `evflow-no-ldi-events` (also ldi=on, ldi_event_weight 0) and "
       "`evflow` (the full model: ldi_event_weight 0.1); a method sets the keys it does not name to off (weights 0, "
       "blur_upsample 1, ldi off, ldi_event_weight 0.1). The paper's ablation rows are these methods in this order "
       "from `blur-only` ([experiments.md](experiments.md)). Applied after `preset` and before the other keys of a "
       "config file; on the command line, in order"},
      field("iterations", &TrainConfig::iterations, "optimisation steps, one training view per step"),
      field("init", &TrainConfig::init,
            "what the Gaussians start from: `random` (`init_gaussians` of them, below) or `points` (one per sparse "
            "point of the dataset, `points3D.npy` from `evflow poses`: its colour, a scale from its 3 nearest "
            "neighbours)"),
      field("init_gaussians", &TrainConfig::init_gaussians,
            "random Gaussians seeded in the training views' frustums between near and far, coloured from their pixel"),
      field("seed", &TrainConfig::seed, "initialisation and view order"),
      {"log_every",
       [](TrainConfig& c, const std::string& v) {
         c.log_every = uint32_t(std::max<uint64_t>(1, to_uint("log_every", v)));
       },
       [](const TrainConfig& c) { return nlohmann::json(c.log_every); },
       "a log line every this many steps (0 reads as 1)"},
      field("checkpoint_every", &TrainConfig::checkpoint_every,
            "`RUN/checkpoint.ckpt` every this many steps (0: only at the end); also on Ctrl-C"),
  };
}

std::vector<Setting> image_settings() {
  return {
      {"sh_degree",
       [](TrainConfig& c, const std::string& v) {
         const uint64_t d = to_uint("sh_degree", v);
         if (d > 3) throw std::invalid_argument("config key 'sh_degree' must be 0..3, got '" + v + "'");
         c.sh_degree = int(d);
       },
       [](const TrainConfig& c) { return nlohmann::json(c.sh_degree); }, "largest spherical-harmonics degree (0..3)"},
      field("sh_increase_every", &TrainConfig::sh_increase_every,
            "the active SH degree grows by one every this many steps. Bands above it cost nothing until they "
            "become active: the projection does not read them, the backward does not add to them, and Adam only "
            "counts their steps (their gradient and moments are zero, so is their update)"),
      field("lr_means_init", &TrainConfig::lr_means_init,
            "Adam learning rate of the means at the start, × the scene extent"),
      field("lr_means_final", &TrainConfig::lr_means_final,
            "… at the end (exponential decay from `lr_means_init` over the run)"),
      field("lr_sh_dc", &TrainConfig::lr_sh_dc, "learning rate of the SH degree-0 (base colour) coefficients"),
      field("lr_sh_rest", &TrainConfig::lr_sh_rest, "learning rate of the higher SH coefficients"),
      field("lr_opacity", &TrainConfig::lr_opacity, "learning rate of the opacity logits"),
      field("lr_log_scales", &TrainConfig::lr_log_scales, "learning rate of the log scales"),
      field("lr_quats", &TrainConfig::lr_quats, "learning rate of the rotation quaternions"),
      field("ssim_lambda", &TrainConfig::ssim_lambda, "λ of the image loss (1−λ)·L1 + λ·(1 − SSIM)"),
      field("loss_space", &TrainConfig::loss_space,
            "where the L1 + D-SSIM term compares the model image with the target: `srgb` (the linear blur mean "
            "re-encoded to sRGB, against the image as stored and scored; in plain mode the render itself, as "
            "3DGS) or `linear` (both decoded to linear light). Splat colours are sRGB either way "
            "([architecture.md](architecture.md#colour-spaces)); the measurement behind the default is in "
            "[experiments.md](experiments.md)"),
      field("target", &TrainConfig::target,
            "what a training view is fitted to: `blurry` (its blurry input), `sharp` (its sharp ground truth, for "
            "sharp data) or `edi` (the blurry image deblurred at mid-exposure by EDI with the dataset's events "
            "and thresholds, clamped to [0, 1]: the 3DGS+EDI baseline)"),
      field("antialiased", &TrainConfig::antialiased, "opacity compensation of the antialiased rasterizer mode"),
      field("background", &TrainConfig::background, "background colour r,g,b (sRGB, as splat colours)"),
  };
}

std::vector<Setting> blur_settings() {
  return {
      field("mode", &TrainConfig::mode,
            "`plain`: each image is one render (3DGS); `blur`: each blurry image is the mean of 2N+1 renders, "
            "decoded to linear light, along the view's learned Bézier exposure trajectory (9 se(3) knots, paper "
            "Sec. 4.1, [trajectory.md](trajectory.md)), the blur-only baseline of the paper"),
      bounded("virtual_frames", &TrainConfig::virtual_frames, 0u, 32u, "N: 2N+1 virtual poses per exposure (0..32)"),
      field("blur_upsample", &TrainConfig::blur_upsample,
            "M of the flow-upsampled blur (paper Eq. 9): each interval of the virtual frames adds M−1 sub-frames, "
            "its first frame moved m/M of the way along the interval's optical flow (`flow`), and the blurry "
            "image is the mean of all 2NM+1 in linear light; 1: off (the paper: 4); > 1 needs `mode=blur`"),
      field("upsample_from", &TrainConfig::upsample_from,
            "fraction of the blur steps with the plain 2N+1-frame mean before the upsampled blur (`blur_upsample`) "
            "starts, counted as `event_from` is; 0: from the first step (the paper)"),
      field("edi_warmup", &TrainConfig::edi_warmup,
            "fraction of the run's first steps that fit one render per step, the view's trajectory at "
            "mid-exposure, to the view's EDI image (as `target=edi`), before the blur model and its terms take "
            "over: a warm-up step costs one render instead of 2N+1, so the splats learn the scene's shape and "
            "colours sooner ([training.md](training.md#edi-warm-up)); 0: off; in [0, 1); needs events. With "
            "`ldi=on` the LDI branch waits for the blur steps. The warm-up shifts each trajectory as a whole at the "
            "pose refinement's rate "
            "(`lr_pose_init`); after it, the knots' schedule and the blur terms' fractions (`event_from`, "
            "`event_flip_until`, `flow_model_from`, `joint_from`) count over the blur steps, as in a run of that many "
            "steps; "
            "the Gaussians' schedules over the whole run"),
      field("edi_warmup_motion", &TrainConfig::edi_warmup_motion,
            "fraction of the EDI warm-up's steps, at its start, that fit the virtual frames: each renders one of "
            "the trajectory's 2N+1 frames (cycling per view) against the view's EDI image at that frame's time, "
            "and the Gaussians and every knot learn from it, so the motion and its direction are learned while the "
            "splats are still coarse; the rest of the warm-up fits the mid-exposure frame, keeping the motion's "
            "shape ([training.md](training.md#edi-warm-up)); the knots' schedule then runs over the whole run; 0: "
            "off; in [0, 1]"),
      field("edi_keep_mid", &TrainConfig::edi_keep_mid,
            "after an EDI warm-up, each blur step keeps every trajectory's mid-exposure pose where the warm-up "
            "left it: the knots' gradient loses its part that moves T(0.5) before Adam, and one common shift of "
            "all nine knots after the step restores T(0.5) exactly, so the blur phase learns the motion about "
            "the pose the mid frames fitted to EDI "
            "([training.md](training.md#edi-warm-up)); needs `edi_warmup` > 0"),
      bounded("edi_mid_lr", &TrainConfig::edi_mid_lr, 0.0, 0.1,
              "with `edi_keep_mid`, the rate at which each mid-exposure pose still moves: its own six-value Adam "
              "on the gradient part the knots lose, starting at this rate and decaying as the knots' rate does, "
              "so a view the warm-up left a pixel off can settle; 0: held exactly; in [0, 0.1]"),
      field("splats_from", &TrainConfig::splats_from,
            "fraction of the blur steps before which the Gaussians are frozen and only the knots learn: the blur "
            "loss fits the exposure's motion to the splats as they are instead of blurring them to match a "
            "trajectory that has no motion yet ([training.md](training.md#edi-warm-up)); counted over the blur steps "
            "after an EDI warm-up; 0: off; in [0, 1)"),
      field("lr_trajectory_init", &TrainConfig::lr_trajectory_init,
            "the knots' Adam learning rate at the start; the fast preset's 1500 steps leave the paper's "
            "1e-3 → 1e-5 too little room to learn the exposure motion"),
      field("lr_trajectory_final", &TrainConfig::lr_trajectory_final,
            "… at the end (exponential decay from `lr_trajectory_init`)"),
      bounded("trajectory_init_sigma", &TrainConfig::trajectory_init_sigma, 0.0, 0.1,
              "standard deviation of the knots' start values (se(3) components, radians and scene units, i.i.d. "
              "around the view's pose; [trajectory.md](trajectory.md)), in [0, 0.1]; the knots start nearly equal, "
              "so the first blur-only steps move them alike, and the motion grows from this spread"),
  };
}

std::vector<Setting> event_settings() {
  return {
      field("event_weight", &TrainConfig::event_weight,
            "λ of the event loss L_ev^gs (paper Eq. 5; [losses.md](losses.md)); 0: off; > 0 needs `mode=blur` "
            "and events"),
      field("event_theta_pos", &TrainConfig::event_theta_pos,
            "threshold Θ+ of the event loss and of EDI targets; 0: the dataset's (`simulator.events` in "
            "dataset.json), else 0.2"),
      field("event_theta_neg", &TrainConfig::event_theta_neg, "threshold Θ−, as `event_theta_pos`"),
      field("event_from", &TrainConfig::event_from,
            "fraction of the run before which the event term is off (its value reads 0): its gradients swamp a "
            "model that does not resemble the scene yet (log-luminance differences of a poor render are noise)"),
      field("event_flip_until", &TrainConfig::event_flip_until,
            "direction check: the blur loss cannot tell a trajectory from its time reversal, the events can. "
            "Until this fraction of the run, each blur+events step also scores the time-reversed frame order "
            "with the event loss and reverses the view's trajectory (knots and their Adam moments) when that "
            "is lower by `event_flip_margin`; that step's update is the flip"),
      field("event_flip_margin", &TrainConfig::event_flip_margin,
            "the margin of the direction check, relative: the reversed order must score below (1 - margin) times "
            "the forward order's value"),
      field("event_norm_floor", &TrainConfig::event_norm_floor,
            "per-pixel RMS below which the event loss holds a norm at its floor (static frame pairs)"),
      field("event_pool", &TrainConfig::event_pool,
            "side of the square cells (pixels) that both sides of the event losses (L_ev^gs, L_ev^w, the "
            "direction check) are summed over before they are compared; 1: per pixel. Summing averages the events' "
            "per-pixel error (threshold quantisation and spread, noise), which otherwise pulls a good model "
            "towards a quantised target ([losses.md](losses.md))"),
      field("event_weight_end", &TrainConfig::event_weight_end,
            "the event terms' weights (L_ev^gs, L_ev^w) at the last step, as a fraction of `event_weight` and "
            "`warp_weight`: they fall linearly to it from the end of the direction check (`event_flip_until`), "
            "once the trajectories' direction and order are settled, so that the blur loss finishes the model; "
            "1: constant. 0 chosen on the objects scene and checked on the default scene "
            "([experiments.md](experiments.md#what-the-event-term-costs))"),
      field("warp_weight", &TrainConfig::warp_weight,
            "λ of the warped-event loss L_ev^w (paper Eq. 6-7: each interval's events moved along its optical "
            "flow to the interval's end, against the frame's edges moved by the flow; [losses.md](losses.md)); "
            "0: off; > 0 needs `mode=blur` and events with times. Shares `event_from`, `event_norm_floor` and "
            "the thresholds with the event loss"),
      field("flow", &TrainConfig::flow,
            "the optical flow of `warp_weight` and `blur_upsample`: `events` (contrast maximisation on each view's "
            "events, [flow.md](flow.md); cached under DATA/.evflow-cache/flow/), `gt` (the simulator's ground "
            "truth, for ablations; refused on data without it) or `model` (from the current splats: their depth "
            "at t_i lifted with the trajectory's pose at t_i and projected with the pose at t_{i+1}; pixels with "
            "accumulated opacity below 0.5 get none; refreshed every `flow_refresh` steps)"),
      field("flow_refresh", &TrainConfig::flow_refresh,
            "steps between two computations of the model's flow (`flow=model` or `flow_model_from`), all views "
            "at once; it is computed only while a term uses it (the warped-event loss from `event_from`, the "
            "upsampled blur always); >= 1"),
      field("flow_model_from", &TrainConfig::flow_model_from,
            "mixed flow: fraction of the run from which the model's flow replaces `flow=events` or `gt` "
            "(refreshed every `flow_refresh` steps); 0: never (with `flow=model`: the model's flow from the "
            "start, and this must stay 0); in [0, 1]"),
  };
}

std::vector<Setting> residual_settings() {
  return {
      field("res_weight", &TrainConfig::res_weight,
            "λ of the event-residual loss L_res (paper Eq. 9): the virtual frames' differences from the middle "
            "frame against the residual prior's R(t_i) = I(t_i) − I(t_N), predicted once per view from its "
            "blurry image and events ([residual_prior.md](residual_prior.md)); 0: off (the paper: 0.1); > 0 "
            "needs `mode=blur`, events with times and `virtual_frames` equal to the prior's N (3)"),
      field("res_prior", &TrainConfig::res_prior,
            "the residual prior's weights (safetensors from `evflow train-prior`); a relative path not found "
            "from the working directory is read from the source tree"),
  };
}

std::vector<Setting> pose_settings() {
  return {
      field("pose_refine", &TrainConfig::pose_refine,
            "plain mode: learn an se(3) delta per training view, c2w' = c2w·Exp(δ) (gradient: the rasterizer's "
            "pose gradient through J_r(δ)^T); eval renders the refined pose"),
      field("lr_pose_init", &TrainConfig::lr_pose_init, "its Adam learning rate at the start"),
      field("lr_pose_final", &TrainConfig::lr_pose_final, "… at the end (exponential decay from `lr_pose_init`)"),
  };
}

std::vector<Setting> density_settings() {
  return {
      field("densify", &TrainConfig::densify, "adaptive density control ([density_control.md](density_control.md))"),
      field("densify_from", &TrainConfig::densify_from, "first step of refinement"),
      field("densify_until", &TrainConfig::densify_until, "no refinement from this step on"),
      field("densify_every", &TrainConfig::densify_every, "steps between refinements"),
      field("densify_grad_threshold", &TrainConfig::densify_grad_threshold,
            "grow where the mean screen-space gradient (× width/2) exceeds this"),
      field("prune_screen_px", &TrainConfig::prune_screen_px,
            "after the first opacity reset, prune Gaussians whose screen radius (3σ, px) exceeds this (0: off; "
            "3DGS: 20; off by default, [density_control.md](density_control.md) says why)"),
      field("prune_world_scale", &TrainConfig::prune_world_scale,
            "after the first opacity reset, prune Gaussians larger than this × the scene extent (0: off; "
            "3DGS: 0.1; off by default, as `prune_screen_px`)"),
      field("opacity_reset_every", &TrainConfig::opacity_reset_every,
            "opacities clamped to 0.01 every this many steps while refining"),
      field("max_gaussians", &TrainConfig::max_gaussians,
            "cap on the Gaussian count (0: none); growth goes to the largest gradients first"),
  };
}

std::vector<Setting> ldi_settings() {
  return {
      field("ldi", &TrainConfig::ldi,
            "the learnable double integral branch (paper Sec. 4.5, [ldi.md](ldi.md)): a small network turns each "
            "view's events into sharp frames C_ldi(t_i) = B / E(t_i) at the virtual frames' times, trained by "
            "L_ldi = L_blur^ldi + λ L_ev^ldi and tied to the renders by L_joint; `on`/`off`; needs `mode=blur` and "
            "events with times"),
      {"ldi_widths",
       [](TrainConfig& c, const std::string& v) {
         const auto w = to_uint_list("ldi_widths", v);
         if (w.size() < 2 || w.front() != 32 || w.back() != 1)
           throw std::invalid_argument("config key 'ldi_widths' must start with 32 and end with 1, got '" + v + "'");
         c.ldi_widths = w;
       },
       [](const TrainConfig& c) { return nlohmann::json(uint_list_text(c.ldi_widths)); },
       "the LDI network's channels: 32 (16 time bins × 2 polarities), each 3×3 layer's output, 1; the paper's "
       "32,64,128,64,16,1 costs 25× the default's multiply-adds per pixel ([ldi.md](ldi.md#speed))"},
      field("ldi_crop", &TrainConfig::ldi_crop,
            "side of the random square crop of the view the LDI branch trains on each step (0: the whole image)"),
      field("ldi_blur_weight", &TrainConfig::ldi_blur_weight,
            "weight of L_blur^ldi: the LDI frames' mean (linear light) against the blurry input, the image loss of "
            "the blur term (`ssim_lambda`, `loss_space`)"),
      field("ldi_event_weight", &TrainConfig::ldi_event_weight,
            "λ of L_ev^ldi, the event loss on the LDI frames (thresholds, `event_pool`, `event_norm_floor` as "
            "L_ev^gs); on from the first step at this constant weight (the splats' schedule does not apply); 0: off"),
      field("joint_weight", &TrainConfig::joint_weight,
            "weight of L_joint (paper Eq. 10): the image loss between each LDI frame and the render at its time, "
            "gradients into both, times the crop's share of the view (`ldi_crop`), so that per render pixel it weighs "
            "what the paper's L_joint over whole images does; 0: off"),
      field("joint_from", &TrainConfig::joint_from,
            "L_joint is on from this fraction of the run (0: from the first step, where the LDI frames, which run "
            "forwards in time from their pre-fit, set each exposure's direction: [ldi.md](ldi.md))"),
      field("joint_ldi_share", &TrainConfig::joint_ldi_share,
            "the share of L_joint's gradient that reaches the LDI frames: 1, the paper's Eq. 10 (both sides); 0, "
            "the joint loss teaches the splats only and the LDI learns from its own terms ([ldi.md](ldi.md)); in "
            "[0, 1]"),
      field("ldi_anchor_weight", &TrainConfig::ldi_anchor_weight,
            "weight of the LDI's anchor to EDI: the pre-fit's regression (log E - log D)^2 to EDI's double "
            "integral with the dataset's thresholds, at the frames' times over the crop, kept as a term in training "
            "([ldi.md](ldi.md)); 0: off (the network then drifts from EDI, losing contrast)"),
      field("ldi_lr", &TrainConfig::ldi_lr, "the LDI network's Adam learning rate (eps 1e-8), as EVDI"),
      field("ldi_init_steps", &TrainConfig::ldi_init_steps,
            "steps of the initialisation to EDI before training: the network regressed to EDI's double integral "
            "with the dataset's thresholds on random crops (0: He initialisation only)"),
      field("ldi_init_lr", &TrainConfig::ldi_init_lr, "the initialisation's Adam learning rate"),
  };
}

const std::vector<Group>& settings_groups() {
  static const std::vector<Group> groups = {
      {"Run", run_settings()},
      {"Gaussians and the image loss", image_settings()},
      {"Blur mode (exposure trajectories)", blur_settings()},
      {"Event loss", event_settings()},
      {"Residual prior", residual_settings()},
      {"Pose refinement (plain mode)", pose_settings()},
      {"Density control", density_settings()},
      {"Learnable double integral", ldi_settings()},
  };
  return groups;
}

const Setting* find_setting(const std::string& key) {
  for (const Group& g : settings_groups())
    for (const Setting& s : g.settings)
      if (s.key == key) return &s;
  return nullptr;
}

// A JSON value as the text `set` parses; arrays of three numbers become "r,g,b".
std::string json_as_text(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_array() && v.size() == 3)
    return std::to_string(v[0].get<double>()) + "," + std::to_string(v[1].get<double>()) + "," +
           std::to_string(v[2].get<double>());
  if (v.is_number_integer() || v.is_number_unsigned()) return std::to_string(v.get<long long>());
  return v.dump();
}

// A default as the docs show it: numbers in their shortest exact form, small ones as "2.5e-3".
std::string display_text(const nlohmann::json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s;
    for (auto& x : v) s += (s.empty() ? "" : ",") + display_text(x);
    return s;
  }
  if (!v.is_number_float()) return v.dump();
  const double d = v.get<double>();
  const bool small = d != 0 && std::abs(d) < 1e-2;
  char buf[32];
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, small ? "%.*e" : "%.*g", small ? prec - 1 : prec, d);
    if (std::stod(buf) == d) break;
  }
  std::string s = buf;
  const size_t e = s.find('e');
  if (e != std::string::npos) {
    size_t digits = e + 1;
    if (s[digits] == '+' || s[digits] == '-') ++digits;
    const size_t nz = s.find_first_not_of('0', digits);
    s = s.substr(0, e + 1) + (s[e + 1] == '-' ? "-" : "") + s.substr(nz == std::string::npos ? s.size() - 1 : nz);
  }
  return s;
}

}  // namespace

const char* loss_space_name(LossSpace s) { return s == LossSpace::Linear ? "linear" : "srgb"; }
const char* init_name(InitSource s) { return s == InitSource::Random ? "random" : "points"; }
const char* mode_name(TrainMode m) { return m == TrainMode::Plain ? "plain" : "blur"; }
const char* flow_source_name(FlowSource f) {
  return f == FlowSource::Events ? "events" : f == FlowSource::Gt ? "gt" : "model";
}
const char* target_name(TrainTarget t) {
  switch (t) {
    case TrainTarget::Blurry:
      return "blurry";
    case TrainTarget::Sharp:
      return "sharp";
    case TrainTarget::Edi:
      return "edi";
  }
  return "?";
}

TrainConfig TrainConfig::preset_named(const std::string& name) {
  TrainConfig c;
  if (name == "fast") {
    c.preset = "fast";
  } else if (name == "paper") {
    c.preset = "paper";
    c.iterations = 40000;
    c.init_gaussians = 100000;
    c.sh_increase_every = 1000;
    c.max_gaussians = 0;
    c.checkpoint_every = 5000;
    c.lr_trajectory_init = 1e-3;
    c.lr_trajectory_final = 1e-5;
    c.ldi_widths = {32, 64, 128, 64, 16, 1};
    c.ldi_crop = 0;
  } else {
    throw std::invalid_argument("unknown preset '" + name + "' (fast, paper)");
  }
  return c;
}

namespace {

// What each method sets; every method sets all of these, so methods do not stack.
struct MethodSpec {
  const char* name;
  TrainMode mode;
  TrainTarget target;
  double event_weight, warp_weight;
  uint32_t blur_upsample;
  double res_weight;
  bool ldi;
  double ldi_event_weight;
};

const std::vector<MethodSpec>& method_specs() {
  using M = TrainMode;
  using T = TrainTarget;
  static const std::vector<MethodSpec> specs = {
      {"plain", M::Plain, T::Blurry, 0, 0, 1, 0, false, 0.1},
      {"edi", M::Plain, T::Edi, 0, 0, 1, 0, false, 0.1},
      {"blur-only", M::Blur, T::Blurry, 0, 0, 1, 0, false, 0.1},
      {"blur+events", M::Blur, T::Blurry, 0.1, 0, 1, 0, false, 0.1},
      {"blur+events+warp", M::Blur, T::Blurry, 0.1, 0.1, 1, 0, false, 0.1},
      {"blur+events+flow", M::Blur, T::Blurry, 0.1, 0.1, 4, 0, false, 0.1},
      {"blur+res", M::Blur, T::Blurry, 0, 0, 1, 0.1, false, 0.1},
      {"blur+events+warp+res", M::Blur, T::Blurry, 0.1, 0.1, 1, 0.1, false, 0.1},
      {"evflow-no-ldi-events", M::Blur, T::Blurry, 0.1, 0.1, 1, 0.1, true, 0},
      {"evflow", M::Blur, T::Blurry, 0.1, 0.1, 1, 0.1, true, 0.1},
  };
  return specs;
}

}  // namespace

std::vector<std::string> TrainConfig::methods() {
  std::vector<std::string> names;
  for (const MethodSpec& m : method_specs()) names.push_back(m.name);
  return names;
}

void TrainConfig::apply_method(const std::string& name) {
  for (const MethodSpec& m : method_specs()) {
    if (name != m.name) continue;
    mode = m.mode, target = m.target;
    event_weight = m.event_weight, warp_weight = m.warp_weight;
    blur_upsample = m.blur_upsample;
    res_weight = m.res_weight;
    ldi = m.ldi, ldi_event_weight = m.ldi_event_weight;
    return;
  }
  std::string all;
  for (const MethodSpec& m : method_specs()) all += std::string(all.empty() ? "" : ", ") + m.name;
  throw std::invalid_argument("unknown method '" + name + "' (" + all + ")");
}

void TrainConfig::set(const std::string& key, const std::string& value) {
  const Setting* s = find_setting(key);
  if (!s) throw std::invalid_argument("unknown config key '" + key + "' (evflow train --keys lists the keys)");
  s->set(*this, value);
}

void TrainConfig::apply_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("config must be a JSON object");
  for (const char* first : {"preset", "method"})
    if (j.contains(first)) set(first, j[first].get<std::string>());
  for (auto& [k, v] : j.items())
    if (k != "preset" && k != "method") set(k, json_as_text(v));
}

nlohmann::json TrainConfig::to_json() const {
  nlohmann::json j = nlohmann::json::object();
  for (const Group& g : settings_groups())
    for (const Setting& s : g.settings)
      if (s.get) j[s.key] = s.get(*this);
  return j;
}

std::vector<std::string> TrainConfig::keys() {
  std::vector<std::string> k;
  for (const Group& g : settings_groups())
    for (const Setting& s : g.settings) k.push_back(s.key);
  return k;
}

std::vector<SettingDoc> TrainConfig::describe() {
  const TrainConfig def, paper = preset_named("paper");
  std::vector<SettingDoc> rows;
  for (const Group& g : settings_groups())
    for (const Setting& s : g.settings) {
      std::string value = "(none)";
      if (s.get) {
        value = display_text(s.get(def));
        const std::string p = display_text(s.get(paper));
        if (p != value && s.key != "preset") value += " (paper: " + p + ")";
      }
      rows.push_back({g.title, s.key, value, s.doc});
    }
  return rows;
}

std::string TrainConfig::describe_markdown() {
  std::string md, group;
  for (const SettingDoc& r : describe()) {
    if (r.group != group) {
      md += (group.empty() ? "" : "\n") + std::string("#### ") + r.group +
            "\n\n| key | default | meaning |\n|---|---|---|\n";
      group = r.group;
    }
    md += "| `" + r.key + "` | " + r.value + " | " + r.doc + " |\n";
  }
  return md;
}

void require_fraction(const char* key, double value, bool one_allowed) {
  if (value >= 0 && (one_allowed ? value <= 1 : value < 1)) return;
  throw std::invalid_argument(std::string(key) + " must be in [0, 1" + (one_allowed ? "]" : ")") + ", got " +
                              std::to_string(value));
}

}  // namespace evflow
