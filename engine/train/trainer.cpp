#include "train/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>
#include <tuple>

#include "loss/event_loss.h"
#include "loss/image_losses.h"
#include "loss/residual_loss.h"
#include "loss/warped_event_loss.h"
#include "prior/residual_prior.h"
#include "train/training_flows.h"

namespace evflow {

namespace {

// Wall-clock laps of a step.
class StepClock {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }
  double total() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
};

}  // namespace

uint32_t view_for_step(uint32_t step, size_t views, uint64_t seed) {
  std::vector<uint32_t> order(views);
  for (uint32_t i = 0; i < views; ++i) order[i] = i;
  std::mt19937_64 rng(seed * 1000003 + (step - 1) / views);
  std::shuffle(order.begin(), order.end(), rng);
  return order[(step - 1) % views];
}

Trainer::Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg)
    : Trainer(ctx, data, cfg, Checkpoint{0, initial_cloud(data, cfg), {}}) {}

Trainer::Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg, const Checkpoint& start)
    : ctx_(ctx),
      data_(data),
      cfg_(std::move(cfg)),
      raster_(ctx),
      cmd_(ctx),
      v_alpha_(ctx, 16, "v_alpha"),
      preview_(ctx),
      step_(start.step) {
  setup(start);
  optimizer_->load(start.optimizer);
  cameras_->load(start.trajectories, cfg_);
}

Checkpoint Trainer::checkpoint() const {
  Checkpoint c{step_, params_->download(), optimizer_->state(), cameras_->state(), std::nullopt, {}};
  if (ldi_) c.ldi = ldi_->state();
  return c;
}

void Trainer::add_loss(std::unique_ptr<ExposureLossTerm> term) {
  if (cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("loss term '" + term->name() + "' needs the virtual frames of mode=blur");
  terms_.add(std::move(term));
}

void Trainer::setup(const Checkpoint& checkpoint) {
  const GaussianCloud& start = checkpoint.cloud;
  if (data_.train.empty()) throw std::invalid_argument("dataset has no training views");
  check_edi_warmup(cfg_, data_);
  require_fraction("splats_from", cfg_.splats_from, false);
  if (cfg_.splats_from > 0 && cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("splats_from > 0 needs mode=blur (the knots learn alone in the first blur steps)");
  const Camera& c0 = data_.train[0].camera;
  for (auto& v : data_.train)
    if (v.camera.width != c0.width || v.camera.height != c0.height)
      throw std::invalid_argument("training views differ in size ('" + v.name +
                                  "'); one size per dataset is supported");
  start.validate("initial Gaussians");
  params_ = std::make_unique<GaussianBuffers>(ctx_, start.size(), start.sh_degree, "p_");
  grads_ = std::make_unique<GaussianBuffers>(ctx_, start.size(), start.sh_degree, "v_");
  params_->upload(start);
  upload_targets();
  const size_t hw = size_t(c0.width) * c0.height;
  v_alpha_ = gpu::Buffer(ctx_, hw * 4, "v_alpha");
  v_alpha_.write(std::vector<float>(hw, 0.0f));
  cameras_ = std::make_unique<CameraModel>(data_, cfg_);
  const uint32_t frames = uint32_t(cameras_->frame_times().size());
  exposure_ = std::make_unique<ExposureRender>(ctx_, frames);
  require_fraction("upsample_from", cfg_.upsample_from);
  set_image_model(upsample_at(step_ + 1));
  add_loss(std::make_unique<BlendLoss>(ctx_, ImageShape{3, c0.height, c0.width}, float(cfg_.ssim_lambda), 1.0f));
  if (cfg_.event_weight > 0) add_event_term();
  if (cfg_.res_weight > 0) add_residual_term();
  setup_flows();
  if (cfg_.ldi) add_ldi_branch(checkpoint);
  if (cfg_.edi_warmup > 0) warmup_ = std::make_unique<EdiWarmup>(ctx_, data_, cfg_, cameras_->frame_times());
  optimizer_ = std::make_unique<GaussianOptimizer>(ctx_, cmd_, *params_, *grads_, cfg_, scene_extent(data_));
}

// The LDI branch from the checkpoint's LDI state, or initialised (at step 0); its terms join the list.
void Trainer::add_ldi_branch(const Checkpoint& start) {
  if (start.step > 0 && !start.ldi)
    throw std::invalid_argument("continuing an ldi=on run at step " + std::to_string(start.step) +
                                " needs the LDI's state (RUN/ldi.safetensors)");
  const std::vector<double>& u = cameras_->frame_times();
  ldi_ = std::make_unique<LdiBranch>(ctx_, data_, cfg_, u, start.ldi ? &*start.ldi : nullptr, start.ldi_source);
  for (auto [term, scheduled] : ldi_->terms()) terms_.add_branch_term(term, scheduled);
}

// Per view, its training target in loss_space.
void Trainer::upload_targets() {
  for (size_t v = 0; v < data_.train.size(); ++v) {
    const std::vector<float> planar = loss_space_target(data_, v, cfg_);
    targets_.emplace_back(ctx_, planar.size() * 4, "target_" + data_.train[v].name);
    targets_.back().write(planar);
  }
}

// The event loss L_ev^gs on the training views' events, and the time-direction check it drives.
void Trainer::add_event_term() {
  if (cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("event_weight > 0 needs mode=blur (the event loss compares virtual frames)");
  if (!(cfg_.event_weight_end >= 0))
    throw std::invalid_argument("event_weight_end must be >= 0, got " + std::to_string(cfg_.event_weight_end));
  events_ = training_events(ctx_, data_);
  auto [pos, neg] = event_thresholds(data_, cfg_);
  EventLossOptions o;
  o.theta_pos = float(pos), o.theta_neg = float(neg), o.norm_floor_rms = float(cfg_.event_norm_floor);
  o.pool = cfg_.event_pool;
  auto term = std::make_unique<EventLoss>(ctx_, *events_, float(cfg_.event_weight), o);
  direction_ =
      std::make_unique<DirectionCheck>(ctx_, *term, cfg_.blur_step(cfg_.event_flip_until), cfg_.event_flip_margin);
  add_loss(std::move(term));
}

// The event-residual loss L_res: the residual prior's R(t_i) of every view, computed once here.
void Trainer::add_residual_term() {
  if (cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("res_weight > 0 needs mode=blur (the residual loss compares virtual frames)");
  const std::vector<double>& u = cameras_->frame_times();
  const Camera& c0 = data_.train[0].camera;
  auto term = std::make_unique<ResidualLoss>(ctx_, c0.width, c0.height, uint32_t(u.size()),
                                             uint32_t(data_.train.size()), float(cfg_.res_weight));
  const auto residuals = prior::predict_residuals(ctx_, cfg_.res_prior, data_, u);
  for (uint32_t v = 0; v < residuals.size(); ++v) term->set_view_residuals(v, residuals[v]);
  residual_ = term.get();
  add_loss(std::move(term));
}

// The training views' interval flows, when the warped-event loss or the upsampled blur needs
// them: estimated from the events (cached), the simulator's ground truth or, with flow=model,
// none yet (the model's flow is computed at the first step that uses it).
void Trainer::setup_flows() {
  const bool warp = cfg_.warp_weight > 0, upsample = cfg_.blur_upsample > 1;
  if (!warp && !upsample) return;
  if (cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("warp_weight > 0 and blur_upsample > 1 need mode=blur (the virtual frames)");
  if (warp && data_.events.size() == 0)
    throw std::invalid_argument("warp_weight > 0 needs an event stream with times, and the dataset in '" + data_.root +
                                "' has none");
  if (cfg_.flow_refresh < 1) throw std::invalid_argument("flow_refresh must be >= 1");
  require_fraction("flow_model_from", cfg_.flow_model_from);
  const bool model = cfg_.flow == FlowSource::Model;
  if (model && cfg_.flow_model_from > 0)
    throw std::invalid_argument(
        "flow_model_from switches flow=events or gt to the model's flow; with flow=model it "
        "must be 0");
  const std::vector<double>& times = cameras_->frame_times();
  const size_t hw = size_t(data_.train[0].camera.width) * data_.train[0].camera.height;
  if (model)
    flows_.assign(data_.train.size(),
                  std::vector<std::vector<float>>(times.size() - 1, std::vector<float>(hw * 2, NAN)));
  else
    flows_ = training_flows(ctx_, data_, cfg_.flow, times);
  if (model || cfg_.flow_model_from > 0) model_flow_ = std::make_unique<ModelFlow>(ctx_);
  if (upsample) {
    const size_t bytes = (times.size() - 1) * hw * 2 * 4;
    ctx_.check_binding_size(bytes, "upsampled blur flow");
    for (uint32_t v = 0; v < data_.train.size(); ++v) {
      flow_planes_.emplace_back(ctx_, bytes, "flow_planes");
      upload_view_flow(v);
    }
  }
  if (warp) add_warp_term();
}

// The warped-event loss L_ev^w: each view's events warped along its intervals' flows.
void Trainer::add_warp_term() {
  const auto planes = warped_event_planes(data_, cfg_, cameras_->frame_times(), flows_);
  WarpedEventOptions o;
  o.norm_floor_rms = float(cfg_.event_norm_floor);
  o.pool = cfg_.event_pool;
  auto term = std::make_unique<WarpedEventLoss>(ctx_, data_.events.width, data_.events.height, planes,
                                                float(cfg_.warp_weight), o);
  warp_ = term.get();
  add_loss(std::move(term));
}

// View v's flow where the terms read it: the upsampled blur's planes and the warped events.
void Trainer::upload_view_flow(uint32_t v) {
  if (!flow_planes_.empty()) {
    std::vector<float> planes;
    for (const auto& d : flows_[v]) append_displacement_planes(d, planes);
    flow_planes_[v].write(planes);
  }
  if (warp_) warp_->set_view_planes(v, view_warped_event_planes(data_, cfg_, cameras_->frame_times(), v, flows_[v]));
}

// The image model of the blur steps, with upsample M (1: the plain mean of the 2N+1 frames).
void Trainer::set_image_model(uint32_t upsample) {
  const Camera& c0 = data_.train[0].camera;
  image_model_ =
      std::make_unique<ImageModel>(ctx_, exposure_->frames(), c0.width, c0.height, cfg_.loss_space, upsample);
}

// The blur's upsample M at a step: blur_upsample from upsample_from on (counted as event_from
// is), before it 1, the plain mean.
uint32_t Trainer::upsample_at(uint32_t step) const {
  const bool started = cfg_.upsample_from <= 0 || step > cfg_.blur_step(cfg_.upsample_from);
  return started ? cfg_.blur_upsample : 1;
}

// The first step that trains with the model's flow (UINT32_MAX: never).
uint32_t Trainer::model_flow_start() const {
  if (!model_flow_) return UINT32_MAX;
  if (cfg_.flow == FlowSource::Model) return 1;
  return cfg_.blur_step(cfg_.flow_model_from) + 1;  // as event_from counts
}

// The model's flow is recomputed when this step uses flow and the last computation is
// flow_refresh steps old (or there was none).
bool Trainer::model_flow_due(bool exposure_on) const {
  if (step_ < model_flow_start()) return false;
  const bool used = !flow_planes_.empty() || (warp_ && exposure_on);
  return used && (model_flow_step_ == 0 || step_ - model_flow_step_ >= cfg_.flow_refresh);
}

void Trainer::refresh_model_flows() {
  StepClock clock;
  for (uint32_t v = 0; v < data_.train.size(); ++v) refresh_model_flow(v);
  model_flow_step_ = step_;
  std::fprintf(stderr, "flow: the model's flow of %zu views at step %u in %.1f s\n", data_.train.size(), step_,
               clock.total() / 1000.0);
}

// View v's flow from the current splats and its trajectory's virtual-frame poses.
void Trainer::refresh_model_flow(uint32_t v) {
  std::vector<Camera> cams;
  for (uint32_t i = 0; i < exposure_->frames(); ++i) cams.push_back(cameras_->frame_camera(v, i));
  flows_[v] = model_flow_->intervals(raster_, *params_, cams, render_settings());
  upload_view_flow(v);
}

RenderSettings Trainer::render_settings() const {
  RenderSettings s;
  s.background = cfg_.background;
  s.antialiased = cfg_.antialiased;
  s.sh_degree = std::min<int>(params_->sh_degree,
                              cfg_.sh_increase_every ? int(step_ / cfg_.sh_increase_every) : params_->sh_degree);
  s.depth = false;  // no training term reads the depth plane; ModelFlow asks for it itself
  return s;
}

StepStats Trainer::step() {
  StepClock clock;
  StepStats st;
  st.step = ++step_;
  st.view = view_for_step(step_, data_.train.size(), cfg_.seed);
  cameras_->begin_step(step_);
  if (warmup_ && warmup_->active(step_)) {
    warmup_step(st);
    return st;
  }
  const bool exposure_on = terms_.has_exposure_terms() && step_ > cfg_.blur_step(cfg_.event_from);
  if (model_flow_due(exposure_on)) refresh_model_flows();
  if (image_model_->upsample() != upsample_at(step_)) set_image_model(upsample_at(step_));
  render_exposure(st.view);
  st.raster_forward_ms = clock.lap();
  cmd_.start_stage_log();
  record_losses(st, exposure_on);
  st.loss_stages = cmd_.take_stage_log();
  st.loss_ms = clock.lap();
  if (ldi_) {
    ldi_->record(cmd_, st.view, step_, exposure_->images(), *image_model_, step_ > cfg_.blur_step(cfg_.joint_from),
                 cfg_.seed * 0x100000001B3ull + step_);
    cmd_.submit();
    st.ldi_ms = clock.lap();
    st.ldi_stages = cmd_.stage_ms();
  }
  read_losses(st, exposure_on, true);
  if (st.flipped && model_flow_step_ > 0) refresh_model_flow(st.view);  // the reversed trajectory's flow
  if (!st.flipped && !st.skipped) {
    if (ldi_) {
      ldi_->backward(cmd_, *image_model_);  // the joint loss's share of the renders' gradients
      cmd_.submit();
      st.ldi_ms += clock.lap();
      st.ldi_stages.insert(st.ldi_stages.end(), cmd_.stage_ms().begin(), cmd_.stage_ms().end());
    }
    backward_raster(st.view);
    st.raster_backward_ms = clock.lap();
    if (step_ > cfg_.blur_step(cfg_.splats_from)) {  // else the knots learn alone (splats_from)
      optimizer_->step(cmd_, raster_.grad2d_norm(), data_.train[st.view].camera, step_, render_settings().sh_degree);
      st.optimizer_ms = clock.lap();
    }
  }
  st.ms = clock.total();
  return st;
}

// One render against the view's EDI image, the blur steps' stages with one frame and no exposure
// terms: the mid-exposure frame, whose pose gradient shifts the view's whole trajectory, or in
// the virtual-frame steps (edi_warmup_motion) a frame against EDI at its time, whose pose
// gradient trains the knots.
void Trainer::warmup_step(StepStats& st) {
  StepClock clock;
  const uint32_t frame = warmup_->frame(step_, st.view, data_.train.size());
  const bool motion = warmup_->motion(step_);
  const Camera camera = motion ? cameras_->frame_camera(st.view, frame) : cameras_->training_camera(st.view);
  warmup_->forward(cmd_, raster_, *params_, camera, render_settings());
  cmd_.submit();
  st.raster_forward_ms = clock.lap();
  terms_.record_image_terms(cmd_, warmup_->image_model(), warmup_->target(st.view, frame));
  cmd_.submit();
  st.loss_ms = clock.lap();
  read_losses(st, false, false);  // no exposure terms, no branch (the LDI waits for the blur steps)
  if (!st.skipped) {
    warmup_->render_grads(cmd_);
    cmd_.submit();
    const lie::Vec6 g = warmup_->backward(raster_, *params_, v_alpha_, *grads_);
    if (motion)
      cameras_->frame_step(st.view, frame, g, step_);
    else
      cameras_->shift_and_step(st.view, g, step_);
    st.raster_backward_ms = clock.lap();
    optimizer_->step(cmd_, raster_.grad2d_norm(), data_.train[st.view].camera, step_, render_settings().sh_degree);
    st.optimizer_ms = clock.lap();
  }
  st.ms = clock.total();
}

// Every frame keeps its render state for the backward pass; the image model takes them all, in
// frame order. The image model's commands are recorded, not submitted: the loss terms that read
// its prediction follow them in the same submit.
void Trainer::render_exposure(uint32_t view) {
  std::vector<Camera> cameras;
  for (uint32_t i = 0; i < exposure_->frames(); ++i) cameras.push_back(cameras_->frame_camera(view, i));
  exposure_->forward(raster_, *params_, cameras, render_settings());
  image_model_->forward(cmd_, exposure_->images(), image_model_->upsample() > 1 ? &flow_planes_[view] : nullptr);
  cmd_.mark("image model");
}

// The loss terms and, in the same submit, the image model's backward to every frame's render
// (recorded even for a step that turns out flipped or skipped, whose renders' gradients are then
// not used); then the direction check's verdict from the values that submit wrote.
void Trainer::record_losses(StepStats& st, bool exposure_on) {
  terms_.record_image_terms(cmd_, *image_model_, targets_[st.view]);
  const bool check = exposure_on && direction_ && direction_->active(step_);
  if (!exposure_on)
    image_model_->render_grads(cmd_, {});
  else if (const std::vector<const gpu::Buffer*> frame_grads = record_exposure_terms(st, check); !frame_grads.empty())
    image_model_->render_grads(cmd_, frame_grads);
  cmd_.mark("render gradients");
  cmd_.submit();
  if (check && direction_->prefers_reversed()) {
    cameras_->flip(st.view);  // this step's gradients belong to the other direction: the flip is the update
    ++flips_;
    st.flipped = true;
  }
}

// Exposure terms add their per-frame gradients on top of each frame's share of the image terms'.
// Without upsampling every frame's share is the mean's gradient itself, which the first term reads
// as its starting point (no copy per frame where it folds). Returns the frames' gradient buffers,
// or nothing when the last term wrote the renders' gradients itself.
std::vector<const gpu::Buffer*> Trainer::record_exposure_terms(const StepStats& st, bool check) {
  const io::View& view = data_.train[st.view];
  const uint32_t frames = exposure_->frames();
  const size_t n_pix = size_t(view.camera.width) * view.camera.height * 3;
  if (frame_grad_.size() != frames)
    for (uint32_t i = 0; i < frames; ++i) frame_grad_.emplace_back(ctx_, n_pix * 4, "frame_grad");
  ExposureFrames ef{st.view,
                    view.camera.width,
                    view.camera.height,
                    view.exposure_start,
                    view.exposure_end,
                    cameras_->frame_times(),
                    {},
                    {},
                    cfg_.seed * 0x100000001B3ull + step_};
  for (uint32_t i = 0; i < frames; ++i) ef.rgb.push_back(&image_model_->linear_frame(i));
  if (check) direction_->score_reversed_next();
  const gpu::Buffer& share = image_model_->mean_grad(cmd_);
  for (uint32_t i = 0; i < frames; ++i) {
    if (image_model_->upsample() == 1)
      ef.grad_in.push_back(&share);
    else
      image_model_->frame_share(cmd_, i, frame_grad_[i]);
    ef.grad.push_back(&frame_grad_[i]);
    ef.render_grad.push_back(&image_model_->render_grad(i));
  }
  cmd_.mark("frame shares");
  const bool rendered = terms_.record_exposure_terms(cmd_, ef, event_schedule());
  if (check) direction_->keep_forward(cmd_);
  return rendered ? std::vector<const gpu::Buffer*>{} : ef.grad;
}

// The event terms' weight factor at this step: 1 until the direction check ends
// (event_flip_until), then falling linearly to event_weight_end at the last step.
double Trainer::event_schedule() const {
  const double from = cfg_.blur_point(cfg_.event_flip_until), to = cfg_.iterations;
  if (cfg_.event_weight_end == 1.0 || double(step_) <= from || !(to > from)) return 1.0;
  const double a = std::min(1.0, (double(step_) - from) / (to - from));
  return 1.0 + a * (cfg_.event_weight_end - 1.0);
}

void Trainer::read_losses(StepStats& st, bool exposure_on, bool branches_on) const {
  LossValues v = terms_.read(exposure_on, branches_on, event_schedule());
  st.term_values = std::move(v.terms);
  st.loss = v.total;
  if (st.flipped || std::isfinite(st.loss)) return;
  st.skipped = true;
  std::fprintf(stderr, "step %u: non-finite loss on view '%s' (term %s): update skipped\n", st.step,
               data_.train[st.view].name.c_str(), v.first_bad ? v.first_bad->name().c_str() : "sum");
}

// Through the rasterizer to the Gaussians and the frames' poses, and on to the view's camera
// parameters (with their Adam step).
void Trainer::backward_raster(uint32_t view) {
  std::vector<const gpu::Buffer*> v_rgb;
  for (uint32_t i = 0; i < exposure_->frames(); ++i) v_rgb.push_back(&image_model_->render_grad(i));
  const std::vector<lie::Vec6> pose = exposure_->backward(raster_, *params_, v_rgb, v_alpha_, *grads_);
  cameras_->backward_and_step(view, pose, step_);
}

ViewSnapshot Trainer::snapshot(uint32_t v, int interval, SnapshotExtras extras) {
  render_exposure(v);
  cmd_.submit();
  const size_t n = size_t(data_.train.at(v).camera.width) * data_.train[v].camera.height * 3;
  ViewSnapshot out{cameras_->frame_times(), exposure_->images(), image_model_->prediction().read<float>(n),
                   targets_[v].read<float>(n)};
  if (cfg_.loss_space == LossSpace::Linear)
    for (auto* img : {&out.model, &out.target})
      for (float& x : *img) x = io::linear_to_srgb(x);
  if (interval >= 0 && !flows_.empty()) {
    out.has_flow = true;
    out.flow = flow_snapshot(v, uint32_t(interval));
  }
  if (extras.residuals && residual_) {
    out.has_residuals = true;
    out.residuals = residual_snapshot(v);
  }
  if (extras.ldi_frames && ldi_) out.ldi_frames = ldi_->view_frames(cmd_, v);
  return out;
}

// After render_exposure(v): the prior's residuals of view v and the frames' F_i - F_N.
ResidualSnapshot Trainer::residual_snapshot(uint32_t v) const {
  const size_t n = size_t(data_.train.at(v).camera.width) * data_.train[v].camera.height * 3;
  const uint32_t frames = exposure_->frames(), mid = frames / 2;
  const std::vector<float> prior = residual_->view_residuals(v);
  const std::vector<float> f_mid = image_model_->linear_frame(mid).read<float>(n);
  ResidualSnapshot r;
  for (uint32_t i = 0, k = 0; i < frames; ++i) {
    if (i == mid) continue;
    std::vector<float> d = image_model_->linear_frame(i).read<float>(n);
    for (size_t j = 0; j < n; ++j) d[j] -= f_mid[j];
    r.frames.push_back(i);
    r.prior.emplace_back(prior.begin() + k * n, prior.begin() + (k + 1) * n);
    r.renders.push_back(std::move(d));
    ++k;
  }
  return r;
}

// After render_exposure(v): interval i's flow and, with the warped-event loss, what it compares
// for the frame i + 1 just rendered.
FlowSnapshot Trainer::flow_snapshot(uint32_t v, uint32_t interval) {
  FlowSnapshot f;
  f.intervals = flow_intervals();
  if (interval >= f.intervals)
    throw std::invalid_argument("flow snapshot: interval " + std::to_string(interval) + " of " +
                                std::to_string(f.intervals));
  f.interval = interval;
  f.width = data_.train[v].camera.width;
  f.height = data_.train[v].camera.height;
  f.flow = flows_[v][interval];
  if (warp_) {
    f.warped = true;
    std::tie(f.measured, f.predicted) = warp_->compared(cmd_, v, interval, image_model_->linear_frame(interval + 1));
  }
  return f;
}

std::vector<float> Trainer::render(const Camera& cam) {
  RenderSettings s = render_settings();
  s.sh_degree = -1;  // every degree the Gaussians have
  raster_.forward(*params_, cam, s, preview_);
  return preview_.outputs().rgb.read<float>(size_t(cam.width) * cam.height * 3);
}

}  // namespace evflow
