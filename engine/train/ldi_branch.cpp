#include "train/ldi_branch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "ldi/crop.h"
#include "ldi/ldi_prefit.h"
#include "train/train_layout.h"
#include "train/training_data.h"

namespace evflow {

namespace {

// view_frames() runs a model of at most this many pixels square, tile by tile.
constexpr uint32_t kViewTile = 256;

std::unique_ptr<GpuEvents> branch_events(gpu::Context& ctx, const io::Dataset& data) {
  if (data.events.size() == 0)
    throw std::invalid_argument("ldi=on needs an event stream with times, and the dataset in '" + data.root +
                                "' has none");
  std::unique_ptr<IntervalEvents> ev = training_events(ctx, data);
  if (!dynamic_cast<GpuEvents*>(ev.get())) throw std::logic_error("ldi: events with times did not load as a stream");
  return std::unique_ptr<GpuEvents>(static_cast<GpuEvents*>(ev.release()));
}

}  // namespace

LdiBranch::LdiBranch(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg,
                     const std::vector<double>& frame_u, const nn::SafetensorsFile* state, const std::string& source)
    : ctx_(ctx), data_(data), cfg_(cfg), frame_u_(frame_u), srgb_(cfg.loss_space == LossSpace::Srgb) {
  if (cfg.mode != TrainMode::Blur)
    throw std::invalid_argument("ldi=on needs mode=blur (its frames pair with the virtual frames)");
  require_fraction("joint_ldi_share", cfg.joint_ldi_share);
  events_ = branch_events(ctx, data);
  const uint32_t W = events_->width(), H = events_->height(), F = uint32_t(frame_u.size());
  const uint32_t cw = cfg.ldi_crop ? std::min(cfg.ldi_crop, W) : W, ch = cfg.ldi_crop ? std::min(cfg.ldi_crop, H) : H;
  model_ = std::make_unique<ldi::LdiModel>(ctx, *events_, cfg.ldi_widths, cw, ch, F);
  crop_ = {0, 0, cw, ch};
  values_ = 3ull * cw * ch;
  const ImageShape shape{3, ch, cw};
  blur_ = std::make_unique<BlendLoss>(ctx, shape, float(cfg.ssim_lambda), float(cfg.ldi_blur_weight));
  blur_->set_name("ldi_blur");
  // L_joint is a mean over the crop: scaled by the crop's share of the view, each render pixel it
  // reaches weighs what it would in the paper's L_joint over whole images (beside L_blur^gs, a
  // mean over the whole view).
  const double crop_share = double(cw) * ch / (double(W) * H);
  joint_ = std::make_unique<ldi::JointLoss>(ctx, shape, float(cfg.ssim_lambda), float(cfg.joint_weight * crop_share));
  if (cfg.ldi_event_weight > 0) {
    crop_events_ = std::make_unique<ldi::CropEvents>(*events_, cw, ch);
    const auto [pos, neg] = event_thresholds(data, cfg);
    EventLossOptions o;
    o.theta_pos = float(pos), o.theta_neg = float(neg), o.norm_floor_rms = float(cfg.event_norm_floor);
    o.pool = cfg.event_pool;
    event_ = std::make_unique<EventLoss>(ctx, *crop_events_, float(cfg.ldi_event_weight), o);
    event_->set_name("ldi_events");
  }
  for (const io::View& v : data.train) {
    std::vector<float> planar = io::planar_rgb(v.blurry);
    blurry_.emplace_back(ctx, planar.size() * 4, "ldi_blurry");
    blurry_.back().write(planar);
    if (srgb_)
      for (float& x : planar) x = io::linear_to_srgb(x);
    target_.emplace_back(ctx, planar.size() * 4, "ldi_target");
    target_.back().write(planar);
  }
  for (auto* b : {&blurry_crop_, &target_crop_, &mean_, &mean_ls_, &v_mean_ls_, &v_mean_, &tmp_})
    *b = gpu::Buffer(ctx, values_ * 4, "ldi_crop_image");
  for (auto* list : {&grad_, &ldi_ls_, &gs_ls_, &g_ldi_ls_, &g_gs_ls_, &g_render_})
    for (uint32_t i = 0; i < F; ++i) list->emplace_back(ctx, values_ * 4, "ldi_frame_image");
  make_anchor_targets();
  adam_ = std::make_unique<Adam>(ctx, AdamOptions{0.9, 0.999, 1e-8});
  model_->add_to(*adam_, float(cfg.ldi_lr));
  if (state)
    load_state(*state, source);
  else
    initialise();
}

// The dataset's thresholds (training_data.h) as EDI's, for the pre-fit and the anchor.
events::EdiThresholds LdiBranch::edi_thresholds() const {
  const auto [pos, neg] = event_thresholds(data_, cfg_);
  return {pos, neg, {}, {}};
}

// He initialisation, then the pre-fit to EDI's double integral with the dataset's thresholds.
void LdiBranch::initialise() {
  model_->init(cfg_.seed * 0x9E3779B97F4A7C15ull + 0x1D1);
  if (cfg_.ldi_init_steps == 0) return;
  const auto start = std::chrono::steady_clock::now();
  ldi::PrefitOptions o;
  o.steps = cfg_.ldi_init_steps;
  o.frames = std::min<uint32_t>(2, model_->max_frames());
  o.lr = float(cfg_.ldi_init_lr);
  o.seed = cfg_.seed;
  o.thresholds = edi_thresholds();
  const ldi::PrefitReport r = ldi::prefit_to_edi(ctx_, *model_, data_.events, *events_, o);
  std::fprintf(stderr,
               "ldi: initialised to EDI (thresholds %.3g / %.3g): %u steps, log-E regression %.4g -> %.4g in %.1f s\n",
               o.thresholds.pos, o.thresholds.neg, r.steps, r.first_loss, r.last_loss,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

// The anchor's targets (ldi_anchor_weight > 0): EDI's double integral of every view at its
// frames' times, with the pre-fit's thresholds.
void LdiBranch::make_anchor_targets() {
  if (cfg_.ldi_anchor_weight < 0 || !std::isfinite(cfg_.ldi_anchor_weight))
    throw std::invalid_argument("ldi_anchor_weight must be a finite weight >= 0");
  if (cfg_.ldi_anchor_weight == 0) return;
  const auto start = std::chrono::steady_clock::now();
  const events::EdiThresholds th = edi_thresholds();
  for (uint32_t v = 0; v < data_.train.size(); ++v) {
    const events::EdiIntegrator edi(data_.events, data_.train[v].exposure_start, data_.train[v].exposure_end, th);
    std::vector<float> d;
    for (double t : frame_times(v))
      for (double x : edi.double_integral(t)) d.push_back(float(x));
    anchor_.emplace_back(ctx_, d.size() * 4, "ldi_anchor");
    anchor_.back().write(d);
  }
  anchor_crop_ = gpu::Buffer(ctx_, frame_u_.size() * model_->pixels() * 4, "ldi_anchor_crop");
  std::fprintf(stderr, "ldi: anchor to EDI (weight %g): %zu views x %zu frame times in %.1f s\n",
               cfg_.ldi_anchor_weight, anchor_.size(), frame_u_.size(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

std::vector<std::pair<LossTerm*, bool>> LdiBranch::terms() {
  std::vector<std::pair<LossTerm*, bool>> t{{blur_.get(), false}};
  if (event_) t.emplace_back(event_.get(), false);
  t.emplace_back(joint_.get(), false);
  return t;
}

ldi::Crop LdiBranch::choose_crop(uint32_t step) const {
  const uint32_t W = events_->width(), H = events_->height();
  ldi::Crop c{0, 0, model_->crop_w(), model_->crop_h()};
  if (c.w == W && c.h == H) return c;
  std::mt19937_64 rng(cfg_.seed * 0x100000001B3ull + step * 0x9E3779B97F4A7C15ull + 0xC0);
  c.x = uint32_t(rng() % (W - c.w + 1));
  c.y = uint32_t(rng() % (H - c.h + 1));
  return c;
}

void LdiBranch::colour(gpu::Commands& cmd, uint32_t op, const gpu::Buffer& x, const gpu::Buffer& g,
                       const gpu::Buffer& y) {
  record_colour(cmd, op, values_, x, g, y);
}

void LdiBranch::record(gpu::Commands& cmd, uint32_t view, uint32_t step, const std::vector<const gpu::Buffer*>& renders,
                       const ImageModel& image_model, bool joint_on, uint64_t seed) {
  const io::View& v = data_.train.at(view);
  const uint32_t W = v.camera.width, H = v.camera.height;
  view_ = view;
  joint_on_ = joint_on;
  crop_ = choose_crop(step);
  ldi::record_crop(cmd, blurry_[view], W, H, 3, crop_, blurry_crop_);
  ldi::record_crop(cmd, target_[view], W, H, 3, crop_, target_crop_);
  if (!anchor_.empty()) ldi::record_crop(cmd, anchor_[view], W, H, uint32_t(frame_u_.size()), crop_, anchor_crop_);
  cmd.mark("ldi crops");
  model_->forward(cmd, view, frame_times(view), crop_, blurry_crop_);
  cmd.mark("ldi frames");
  record_blur(cmd);
  cmd.mark("ldi blur term");
  if (joint_on)
    record_joint(cmd, renders, image_model);
  else
    cmd.fill(joint_->value_buffer(), 0u, uint64_t(joint_->value_offset()) * 4, 4);
  cmd.mark("ldi joint term");
  record_events(cmd, view, seed);
  cmd.mark("ldi event term");
}

// Inside the exposure, whatever the rounding of t_0 + u T.
std::vector<double> LdiBranch::frame_times(uint32_t view) const {
  const io::View& v = data_.train.at(view);
  std::vector<double> times;
  for (double u : frame_u_)
    times.push_back(
        std::clamp(v.exposure_start + u * (v.exposure_end - v.exposure_start), v.exposure_start, v.exposure_end));
  return times;
}

std::vector<std::vector<float>> LdiBranch::view_frames(gpu::Commands& cmd, uint32_t view,
                                                       const std::vector<uint32_t>& only) {
  const uint32_t W = events_->width(), H = events_->height();
  const auto& cam = data_.train.at(view).camera;
  if (cam.width != W || cam.height != H)
    throw std::invalid_argument("ldi: view '" + data_.train[view].name + "' is not of the event sensor's size");
  if (!full_view_) {
    const uint32_t reach = uint32_t(cfg_.ldi_widths.size() - 1);
    full_view_ =
        std::make_unique<ldi::FullViewFrames>(ctx_, *events_, cfg_.ldi_widths, ldi::view_tile_side(W, kViewTile, reach),
                                              ldi::view_tile_side(H, kViewTile, reach), model_->max_frames());
  }
  std::vector<double> times = frame_times(view);
  if (!only.empty()) {
    std::vector<double> picked;
    for (uint32_t i : only) picked.push_back(times.at(i));
    times = picked;
  }
  full_view_->forward(cmd, *model_, view, times, blurry_[view]);
  cmd.submit();
  std::vector<std::vector<float>> frames;
  for (uint32_t i = 0; i < times.size(); ++i) frames.push_back(full_view_->frame(i).read<float>(size_t(3) * W * H));
  return frames;
}

// L_blur^ldi: each frame's gradient starts as its share of the mean's.
void LdiBranch::record_blur(gpu::Commands& cmd) {
  const uint32_t F = model_->frames();
  for (uint32_t i = 0; i < F; ++i) record_accumulate(cmd, values_, 1.0f / float(F), i > 0, model_->frame(i), mean_);
  if (srgb_) colour(cmd, shaderio::kColourEncode, mean_, mean_, mean_ls_);
  blur_->record(cmd, srgb_ ? mean_ls_ : mean_, target_crop_, v_mean_ls_, blur_->weight() / float(F), false);
  if (srgb_) colour(cmd, shaderio::kColourEncodeBwd, mean_, v_mean_ls_, v_mean_);
  for (uint32_t i = 0; i < F; ++i) cmd.copy(srgb_ ? v_mean_ : v_mean_ls_, grad_[i], values_ * 4);
}

// L_joint in loss_space: the LDI frame's gradient (its joint_ldi_share) goes back to linear light
// and adds to the frame's; the render's (the crop of an sRGB render) waits for backward().
void LdiBranch::record_joint(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders, const ImageModel& im) {
  const uint32_t F = model_->frames();
  const uint32_t W = data_.train[view_].camera.width, H = data_.train[view_].camera.height;
  std::vector<const gpu::Buffer*> a, b, ga, gb;
  for (uint32_t i = 0; i < F; ++i) {
    if (srgb_) colour(cmd, shaderio::kColourEncode, model_->frame(i), model_->frame(i), ldi_ls_[i]);
    ldi::record_crop(cmd, srgb_ ? *renders[i] : im.linear_frame(i), W, H, 3, crop_, gs_ls_[i]);
    a.push_back(srgb_ ? &ldi_ls_[i] : &model_->frame(i));
    b.push_back(&gs_ls_[i]);
    ga.push_back(&g_ldi_ls_[i]);
    gb.push_back(srgb_ ? &g_render_[i] : &g_gs_ls_[i]);
  }
  joint_->record(cmd, a, b, ga, gb, joint_->weight(), false);
  const float share = float(cfg_.joint_ldi_share);
  for (uint32_t i = 0; i < F; ++i) {
    if (share > 0) {
      if (srgb_) colour(cmd, shaderio::kColourEncodeBwd, model_->frame(i), g_ldi_ls_[i], tmp_);
      record_accumulate(cmd, values_, share, true, srgb_ ? tmp_ : g_ldi_ls_[i], grad_[i]);
    }
    if (srgb_) continue;
    ldi::record_crop(cmd, *renders[i], W, H, 3, crop_, tmp_);
    colour(cmd, shaderio::kColourDecodeBwd, tmp_, g_gs_ls_[i], g_render_[i]);
  }
}

// L_ev^ldi on the LDI frames over the crop, at every step and a constant weight: the events are
// the network's only source of sharpness (E = 1, the blurry image, satisfies L_blur^ldi), and the
// term reaches the network alone, so the splats' schedule (set by their time-direction check)
// has no reason to apply.
void LdiBranch::record_events(gpu::Commands& cmd, uint32_t view, uint64_t seed) {
  if (!event_) return;
  crop_events_->set_crop(crop_);
  const io::View& v = data_.train[view];
  ExposureFrames ef{view, crop_.w, crop_.h, v.exposure_start, v.exposure_end, frame_u_, {}, {}, seed};
  for (uint32_t i = 0; i < model_->frames(); ++i) {
    ef.rgb.push_back(&model_->frame(i));
    ef.grad.push_back(&grad_[i]);
  }
  event_->record(cmd, ef, float(event_->weight()));
}

void LdiBranch::backward(gpu::Commands& cmd, const ImageModel& image_model) {
  const uint32_t W = data_.train[view_].camera.width, H = data_.train[view_].camera.height;
  std::vector<const gpu::Buffer*> grads;
  for (uint32_t i = 0; i < model_->frames(); ++i) {
    if (joint_on_) ldi::record_uncrop_add(cmd, g_render_[i], W, H, 3, crop_, image_model.render_grad(i));
    grads.push_back(&grad_[i]);
  }
  cmd.mark("ldi joint to renders");
  ldi::LdiAnchor anchor;
  if (!anchor_.empty())
    anchor = {&anchor_crop_, float(cfg_.ldi_anchor_weight / double(model_->frames() * model_->pixels()))};
  model_->backward_from_frames(cmd, grads, 1.0f, anchor);
  adam_->step(cmd);
  cmd.mark("ldi adam");
}

nn::SafetensorsFile LdiBranch::state() const {
  nn::SafetensorsFile f;
  model_->save(f);
  for (size_t i = 0; i < adam_->group_count(); ++i) {
    const AdamGroup& g = adam_->group(i);
    f.tensors.push_back({"adam." + g.name + ".exp_avg", {g.count}, adam_->exp_avg(i).read<float>(g.count)});
    f.tensors.push_back({"adam." + g.name + ".exp_avg_sq", {g.count}, adam_->exp_avg_sq(i).read<float>(g.count)});
  }
  f.metadata["adam_step"] = std::to_string(adam_->group_count() ? adam_->step_count(0) : 0);
  return f;
}

// Weights, and the Adam state when the file has it (a file of weights alone starts Adam afresh).
void LdiBranch::load_state(const nn::SafetensorsFile& f, const std::string& source) {
  model_->load(f, source);
  const auto step = f.metadata.find("adam_step");
  if (step == f.metadata.end()) return;
  for (size_t i = 0; i < adam_->group_count(); ++i) {
    const AdamGroup& g = adam_->group(i);
    const nn::NamedTensor* m = f.find("adam." + g.name + ".exp_avg");
    const nn::NamedTensor* v = f.find("adam." + g.name + ".exp_avg_sq");
    if (!m || !v || m->values.size() != g.count || v->values.size() != g.count)
      throw std::runtime_error(source + ": no Adam state of the right size for " + g.name);
    adam_->load_state(i, m->values, v->values, std::stoull(step->second));
  }
}

}  // namespace evflow
