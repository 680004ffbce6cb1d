#include "train/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "events/edi.h"
#include "loss/event_loss.h"
#include "loss/image_losses.h"
#include "optim/host_adam.h"
#include "optim/schedule.h"
#include "train/image_model.h"

namespace evflow {

// Colours for the initial Gaussians: the sharp image when training on it, else the blurry one.
static const io::Image& target_image(const io::View& v, const TrainConfig& cfg) {
  if (cfg.target == TrainTarget::Sharp) {
    if (!v.sharp_mid) throw std::invalid_argument("target=sharp, but view '" + v.name + "' has no sharp image");
    return *v.sharp_mid;
  }
  return v.blurry;
}

std::pair<double, double> event_thresholds(const io::Dataset& data, const TrainConfig& cfg) {
  double pos = 0.2, neg = 0.2;
  const auto& m = data.manifest;
  if (m.is_object() && m.contains("simulator") && m["simulator"].contains("events")) {
    const auto& e = m["simulator"]["events"];
    if (e.contains("theta_pos") && e["theta_pos"].is_number()) pos = e["theta_pos"].get<double>();
    if (e.contains("theta_neg") && e["theta_neg"].is_number()) neg = e["theta_neg"].get<double>();
  }
  if (cfg.event_theta_pos > 0) pos = cfg.event_theta_pos;
  if (cfg.event_theta_neg > 0) neg = cfg.event_theta_neg;
  return {pos, neg};
}

io::Image training_target(const io::Dataset& data, size_t view, const TrainConfig& cfg) {
  const io::View& v = data.train.at(view);
  if (cfg.target != TrainTarget::Edi) return target_image(v, cfg);
  if (data.events.size() == 0)
    throw std::invalid_argument("target=edi needs events, and the dataset in '" + data.root + "' has none");
  if (!(v.exposure_end > v.exposure_start))
    throw std::invalid_argument("target=edi: view '" + v.name + "' has no exposure interval");
  auto [pos, neg] = event_thresholds(data, cfg);
  io::Image out = v.blurry;
  out.data = events::edi_deblur(v.blurry.data.data(), v.blurry.channels, data.events, v.exposure_start, v.exposure_end,
                                events::EdiThresholds{pos, neg, {}, {}});
  for (float& x : out.data) x = std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 0.0f;  // a training target lives in [0, 1]
  return out;
}

GaussianCloud initial_cloud(const io::Dataset& data, const TrainConfig& cfg) {
  if (data.train.empty()) throw std::invalid_argument("dataset has no training views");
  std::mt19937_64 rng(cfg.seed * 7919 + 17);
  auto uni = [&](double a, double b) { return a + (b - a) * (double(rng() >> 11) * (1.0 / 9007199254740992.0)); };
  const double near = data.near > 0 ? data.near : 0.5, far = data.far > near ? data.far : near * 20;
  GaussianCloud c;
  c.resize(cfg.init_gaussians, cfg.sh_degree);
  const int K = c.coeffs();
  for (size_t i = 0; i < c.size(); ++i) {
    const io::View& v = data.train[rng() % data.train.size()];
    const io::Image& img = target_image(v, cfg);
    const Camera& cam = v.camera;
    const double px = uni(0, cam.width), py = uni(0, cam.height);
    const double z = near * std::pow(far / near, uni(0.05, 0.9));  // log-uniform, away from the bounds
    const double pc[3] = {(px - cam.cx) / cam.fx * z - cam.t[0], (py - cam.cy) / cam.fy * z - cam.t[1], z - cam.t[2]};
    for (int r = 0; r < 3; ++r) c.means[i * 3 + r] = float(cam.R[r] * pc[0] + cam.R[3 + r] * pc[1] + cam.R[6 + r] * pc[2]);
    const float ls = float(std::log(1.5 * z / cam.fx));  // ~1.5 px
    for (int k = 0; k < 3; ++k) c.log_scales[i * 3 + k] = ls;
    c.quats[i * 4] = 1;
    c.quats[i * 4 + 1] = c.quats[i * 4 + 2] = c.quats[i * 4 + 3] = 0;
    c.opacity_logits[i] = float(std::log(0.1 / 0.9));
    const uint32_t ix = std::min<uint32_t>(uint32_t(px), img.width - 1), iy = std::min<uint32_t>(uint32_t(py), img.height - 1);
    for (int ch = 0; ch < 3; ++ch) {
      // Splat colours are display-referred sRGB (image_model.h); images are linear in memory.
      const float col = io::linear_to_srgb(img.data[(size_t(iy) * img.width + ix) * img.channels + std::min<uint32_t>(ch, img.channels - 1)]);
      c.sh[(i * K) * 3 + ch] = float((col - 0.5) / 0.28209479177387814);
      for (int k = 1; k < K; ++k) c.sh[(i * K + k) * 3 + ch] = 0;
    }
  }
  return c;
}

Trainer::Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg)
    : Trainer(ctx, data, cfg, Checkpoint{0, initial_cloud(data, cfg), {}}) {}

Trainer::Trainer(gpu::Context& ctx, const io::Dataset& data, TrainConfig cfg, const Checkpoint& start)
    : ctx_(ctx), data_(data), cfg_(std::move(cfg)), raster_(ctx), cmd_(ctx), v_alpha_(ctx, 16, "v_alpha"), step_(start.step) {
  setup(start.cloud);
  for (auto& g : start.optimizer) adam_->load_state(adam_->group_index(g.name), g.exp_avg, g.exp_avg_sq, g.step);
  if (!start.trajectories.empty()) {
    const size_t want = trajectory_state_.size(), dof = trajectories_.empty() ? 6 : ExposureTrajectory::kSize;
    if (start.trajectories.size() != want || start.trajectories[0].knots.size() != dof)
      throw std::invalid_argument("checkpoint has " + std::to_string(start.trajectories.size()) + " camera states of " +
                                  std::to_string(start.trajectories[0].knots.size()) + " values; this run (mode " + std::string(mode_name(cfg_.mode)) +
                                  (cfg_.pose_refine ? ", pose_refine" : "") + ") has " + std::to_string(want) + " of " +
                                  std::to_string(dof));
    for (size_t v = 0; v < want; ++v) {
      const auto& k = start.trajectories[v].knots;
      if (trajectories_.empty()) std::copy(k.begin(), k.end(), pose_deltas_[v].begin());
      else std::copy(k.begin(), k.end(), trajectories_[v].data());
      trajectory_state_[v] = start.trajectories[v];
    }
  }
}

Checkpoint Trainer::checkpoint() const {
  Checkpoint c{step_, params_->download(), {}};
  for (size_t i = 0; i < adam_->group_count(); ++i) {
    const uint32_t n = adam_->group(i).count;
    const bool fresh = adam_->step_count(i) == 0;  // moments not initialised before the first step
    c.optimizer.push_back({adam_->group(i).name, adam_->step_count(i),
                           fresh ? std::vector<float>(n, 0.f) : adam_->exp_avg(i).read<float>(n),
                           fresh ? std::vector<float>(n, 0.f) : adam_->exp_avg_sq(i).read<float>(n)});
  }
  for (size_t v = 0; v < trajectory_state_.size(); ++v) {
    TrajectoryState t = trajectory_state_[v];
    if (trajectories_.empty()) t.knots.assign(pose_deltas_[v].begin(), pose_deltas_[v].end());
    else t.knots.assign(trajectories_[v].data(), trajectories_[v].data() + ExposureTrajectory::kSize);
    c.trajectories.push_back(std::move(t));
  }
  return c;
}

Camera Trainer::training_camera(uint32_t v) const {
  if (!trajectories_.empty()) return trajectories_.at(v).camera_at(0.5);
  if (!pose_deltas_.empty()) return data_.train.at(v).camera.perturbed(pose_deltas_.at(v));
  return data_.train.at(v).camera;
}

void Trainer::add_loss(std::unique_ptr<LossTerm> term) {
  if (!dynamic_cast<ImageLossTerm*>(term.get()) && !dynamic_cast<ExposureLossTerm*>(term.get()))
    throw std::invalid_argument("loss term '" + term->name() + "' is neither an image nor an exposure term");
  if (dynamic_cast<ExposureLossTerm*>(term.get()) && cfg_.mode != TrainMode::Blur)
    throw std::invalid_argument("loss term '" + term->name() + "' needs the virtual frames of mode=blur");
  terms_.push_back(std::move(term));
}

void Trainer::setup(const GaussianCloud& start) {
  if (data_.train.empty()) throw std::invalid_argument("dataset has no training views");
  const Camera& c0 = data_.train[0].camera;
  for (auto& v : data_.train)
    if (v.camera.width != c0.width || v.camera.height != c0.height)
      throw std::invalid_argument("training views differ in size ('" + v.name + "'); one size per dataset is supported");
  start.validate("initial Gaussians");
  params_ = std::make_unique<GaussianBuffers>(ctx_, start.size(), start.sh_degree, "p_");
  grads_ = std::make_unique<GaussianBuffers>(ctx_, start.size(), start.sh_degree, "v_");
  params_->upload(start);
  for (size_t v = 0; v < data_.train.size(); ++v) {
    auto planar = io::planar_rgb(training_target(data_, v, cfg_));
    if (cfg_.loss_space == LossSpace::Srgb)
      for (float& x : planar) x = io::linear_to_srgb(x);
    targets_.emplace_back(ctx_, planar.size() * 4, "target_" + data_.train[v].name);
    targets_.back().write(planar);
  }
  const size_t hw = size_t(c0.width) * c0.height;
  v_alpha_ = gpu::Buffer(ctx_, hw * 4, "v_alpha");
  v_alpha_.write(std::vector<float>(hw, 0.0f));
  image_model_ = std::make_unique<ImageModel>(ctx_, cfg_.mode == TrainMode::Blur ? 2 * cfg_.virtual_frames + 1 : 1, hw * 3, cfg_.loss_space);
  if (cfg_.mode == TrainMode::Blur) {
    for (size_t v = 0; v < data_.train.size(); ++v) {
      trajectories_.emplace_back(data_.train[v].camera, cfg_.seed * 100003 + v);
      trajectory_state_.push_back({0, {}, std::vector<double>(ExposureTrajectory::kSize, 0.0),
                                   std::vector<double>(ExposureTrajectory::kSize, 0.0)});
    }
  } else if (cfg_.pose_refine) {
    pose_deltas_.assign(data_.train.size(), lie::Vec6{});
    trajectory_state_.assign(data_.train.size(), {0, {}, std::vector<double>(6, 0.0), std::vector<double>(6, 0.0)});
  }
  terms_.clear();
  add_loss(std::make_unique<BlendLoss>(ctx_, ImageShape{3, c0.height, c0.width}, float(cfg_.ssim_lambda), 1.0f));
  if (cfg_.event_weight > 0) {
    if (cfg_.mode != TrainMode::Blur) throw std::invalid_argument("event_weight > 0 needs mode=blur (the event loss compares virtual frames)");
    if (data_.events.size() == 0) throw std::invalid_argument("event_weight > 0, but the dataset in '" + data_.root + "' has no events");
    if (data_.events.width != c0.width || data_.events.height != c0.height)
      throw std::invalid_argument("the events' sensor (" + std::to_string(data_.events.width) + "x" +
                                  std::to_string(data_.events.height) + ") differs from the images (" + std::to_string(c0.width) +
                                  "x" + std::to_string(c0.height) + ")");
    std::vector<EventWindow> windows;
    for (auto& v : data_.train) {
      if (!(v.exposure_end > v.exposure_start))
        throw std::invalid_argument("view '" + v.name + "' has no exposure interval for its events");
      windows.push_back({v.exposure_start, v.exposure_end});
    }
    events_ = std::make_unique<GpuEvents>(ctx_, data_.events, windows, "events of " + data_.root);
    auto [pos, neg] = event_thresholds(data_, cfg_);
    EventLossOptions o;
    o.theta_pos = float(pos), o.theta_neg = float(neg), o.norm_floor_rms = float(cfg_.event_norm_floor);
    add_loss(std::make_unique<EventLoss>(ctx_, *events_, float(cfg_.event_weight), o));
  }

  // Scene extent: radius of the camera centres around their mean (as 3DGS), at least 1.
  double mean[3] = {0, 0, 0};
  for (auto& v : data_.train) { auto c = v.camera.center(); for (int i = 0; i < 3; ++i) mean[i] += c[i] / data_.train.size(); }
  double r = 0;
  for (auto& v : data_.train) {
    auto c = v.camera.center();
    r = std::max(r, std::sqrt((c[0] - mean[0]) * (c[0] - mean[0]) + (c[1] - mean[1]) * (c[1] - mean[1]) + (c[2] - mean[2]) * (c[2] - mean[2])));
  }
  extent_ = std::max(1.0, 1.1 * r);

  adam_ = std::make_unique<Adam>(ctx_);
  const uint32_t n = uint32_t(start.size());
  means_group_ = adam_->add_group({"means", &params_->means, &grads_->means, n * 3, float(cfg_.lr_means_init * extent_), 3});
  adam_->add_group({"log_scales", &params_->log_scales, &grads_->log_scales, n * 3, float(cfg_.lr_log_scales), 3});
  adam_->add_group({"quats", &params_->quats, &grads_->quats, n * 4, float(cfg_.lr_quats), 4});
  adam_->add_group({"opacity_logits", &params_->opacity_logits, &grads_->opacity_logits, n, float(cfg_.lr_opacity), 1});
  adam_->add_group({"sh0", &params_->sh[0], &grads_->sh[0], n * 3, float(cfg_.lr_sh_dc), 3});
  static const uint32_t band[4] = {1, 3, 5, 7};
  for (int l = 1; l <= start.sh_degree; ++l)
    adam_->add_group({"sh" + std::to_string(l), &params_->sh[l], &grads_->sh[l], n * band[l] * 3, float(cfg_.lr_sh_rest), band[l] * 3});

  if (cfg_.densify) {
    DensityConfig d;
    d.refine_from = cfg_.densify_from;
    d.refine_until = cfg_.densify_until;
    d.refine_every = cfg_.densify_every;
    d.grad_threshold = float(cfg_.densify_grad_threshold);
    d.max_screen_radius = float(cfg_.prune_screen_px);
    d.max_world_scale = float(cfg_.prune_world_scale);
    d.reset_every = cfg_.opacity_reset_every;
    d.max_gaussians = cfg_.max_gaussians;
    d.seed = uint32_t(cfg_.seed);
    density_stats_ = std::make_unique<DensityStats>(ctx_);
    density_ = std::make_unique<DensityControl>(ctx_, d);
    density_stats_->reset(cmd_, n);
    cmd_.submit();
  }
}

StepStats Trainer::step() {
  auto t0 = std::chrono::steady_clock::now();
  StepStats st;
  st.step = ++step_;
  // Deterministic view order: a seeded shuffle per epoch.
  const size_t nv = data_.train.size();
  std::vector<uint32_t> order(nv);
  for (uint32_t i = 0; i < nv; ++i) order[i] = i;
  std::mt19937_64 rng(cfg_.seed * 1000003 + (step_ - 1) / nv);
  std::shuffle(order.begin(), order.end(), rng);
  st.view = order[(step_ - 1) % nv];
  const io::View& view = data_.train[st.view];

  RenderSettings s;
  s.background = cfg_.background;
  s.antialiased = cfg_.antialiased;
  s.sh_degree = std::min<int>(params_->sh_degree, cfg_.sh_increase_every ? int(step_ / cfg_.sh_increase_every) : params_->sh_degree);
  auto lap = [t = std::chrono::steady_clock::now()]() mutable {
    auto now = std::chrono::steady_clock::now();
    double ms = std::chrono::duration<double, std::milli>(now - t).count();
    t = now;
    return ms;
  };
  const bool blur = cfg_.mode == TrainMode::Blur;
  const uint32_t frames = blur ? 2 * cfg_.virtual_frames + 1 : 1;
  const std::vector<double> us = blur ? ExposureTrajectory::virtual_times(int(cfg_.virtual_frames)) : std::vector<double>{0.5};
  auto camera_at = [&](uint32_t i) { return blur ? trajectories_[st.view].camera_at(us[i]) : training_camera(st.view); };
  const size_t n_pix = size_t(view.camera.width) * view.camera.height * 3;
  bool exposure_terms = false;
  for (auto& t : terms_) exposure_terms |= dynamic_cast<ExposureLossTerm*>(t.get()) != nullptr;
  if (step_ <= uint32_t(cfg_.event_from * cfg_.iterations)) exposure_terms = false;  // not started yet
  if (exposure_terms && frame_grad_.size() != frames) {
    frame_grad_.clear();
    for (uint32_t i = 0; i < frames; ++i) frame_grad_.emplace_back(ctx_, n_pix * 4, "frame_grad");
  }
  // Forward: every frame keeps its render state (and its image) for the backward pass; the
  // image model (image_model.h) takes them all, in frame order, in one submit.
  std::vector<const gpu::Buffer*> renders;
  for (uint32_t i = 0; i < frames; ++i) {
    frame_raster(i).forward(*params_, camera_at(i), s);
    renders.push_back(&frame_raster(i).outputs().rgb);
  }
  image_model_->forward(cmd_, renders);
  cmd_.submit();
  st.raster_forward_ms = lap();
  // Image terms: every frame's share of d(loss)/d(mean image) is 1/frames of it.
  bool first = true;
  for (auto& t : terms_)
    if (auto* img = dynamic_cast<ImageLossTerm*>(t.get())) {
      img->record(cmd_, image_model_->prediction(), targets_[st.view], image_model_->prediction_grad(),
                  t->weight() / float(frames), !first);
      first = false;
    }
  // Exposure terms add their per-frame gradients on top of that share.
  if (exposure_terms) {
    ExposureFrames ef;
    ef.view = st.view;
    ef.width = view.camera.width, ef.height = view.camera.height;
    ef.t0 = view.exposure_start, ef.t1 = view.exposure_end;
    ef.u = us;
    ef.seed = cfg_.seed * 0x100000001B3ull + step_;
    EventLoss* events = nullptr;
    for (auto& t : terms_)
      if (auto* e = dynamic_cast<EventLoss*>(t.get())) events = e;
    const bool check_flip = events && step_ <= uint32_t(cfg_.event_flip_until * cfg_.iterations);
    double reversed = 0;
    if (check_flip) {
      // Score the time-reversed frame order first (the value alone; the same pairs and counts).
      for (uint32_t i = 0; i < frames; ++i) ef.rgb.push_back(&image_model_->linear_frame(frames - 1 - i));
      cmd_.submit();  // the image terms' value slots are read after the next submit; keep them
      events->record_value(cmd_, ef);
      cmd_.submit();
      reversed = events->value();
      ef.rgb.clear();
    }
    const gpu::Buffer& mean_grad = image_model_->mean_grad(cmd_);
    for (uint32_t i = 0; i < frames; ++i) {
      cmd_.copy(mean_grad, frame_grad_[i], n_pix * 4);
      ef.rgb.push_back(&image_model_->linear_frame(i));
      ef.grad.push_back(&frame_grad_[i]);
    }
    for (auto& t : terms_)
      if (auto* ex = dynamic_cast<ExposureLossTerm*>(t.get())) ex->record(cmd_, ef);
    if (check_flip) {
      cmd_.submit();
      if (std::isfinite(reversed) && reversed + cfg_.event_flip_margin < events->value()) {
        flip_trajectory(st.view);
        st.flipped = true;
      }
    }
  }
  cmd_.submit();
  st.loss_ms = lap();
  st.loss = 0;
  const LossTerm* bad_term = nullptr;
  for (auto& t : terms_) {
    if (!exposure_terms && dynamic_cast<ExposureLossTerm*>(t.get())) {  // not recorded this step
      st.term_values.push_back(0.0);
      continue;
    }
    const double v = t->value();
    st.term_values.push_back(v);
    st.loss += t->weight() * v;
    if (!std::isfinite(v) && !bad_term) bad_term = t.get();
  }
  if (st.flipped) {
    // This step's gradients belong to the other time direction: the flip is the update.
  } else if (!std::isfinite(st.loss)) {
    st.skipped = true;
    std::fprintf(stderr, "step %u: non-finite loss on view '%s' (term %s): update skipped\n", st.step, view.name.c_str(),
                 bad_term ? bad_term->name().c_str() : "sum");
  } else {
    std::vector<const gpu::Buffer*> frame_grads;
    if (exposure_terms)
      for (auto& g : frame_grad_) frame_grads.push_back(&g);
    image_model_->render_grads(cmd_, frame_grads);
    cmd_.submit();  // the rasterizers' backward passes run on their own command buffers
    std::array<double, ExposureTrajectory::kSize> knot_grad{};
    lie::Vec6 pose_grad{};
    for (uint32_t i = 0; i < frames; ++i) {
      Rasterizer& r = frame_raster(i);
      r.backward(*params_, image_model_->render_grad(i), v_alpha_, *grads_, i > 0, &raster_.grad2d_norm());
      if (blur || !pose_deltas_.empty()) {
        auto g = r.pose_gradient();
        const lie::Vec6 g6{g[0], g[1], g[2], g[3], g[4], g[5]};
        if (blur) {
          auto kg = trajectories_[st.view].backward(us[i], g6);
          for (size_t k = 0; k < kg.size(); ++k) knot_grad[k] += kg[k];
        } else {
          // c2w Exp(delta) Exp(g-step) = c2w Exp(delta + J_r(delta)^-1 g-step): dL/ddelta = J_r(delta)^T g.
          pose_grad = lie::mul_transposed(lie::se3_right_jacobian(pose_deltas_[st.view]), g6);
        }
      }
    }
    if (blur) last_camera_grad_.assign(knot_grad.begin(), knot_grad.end());
    else if (!pose_deltas_.empty()) last_camera_grad_.assign(pose_grad.begin(), pose_grad.end());
    if (blur) camera_adam(st.view, knot_grad.data(), cfg_.lr_trajectory_init, cfg_.lr_trajectory_final);
    if (!pose_deltas_.empty()) camera_adam(st.view, pose_grad.data(), cfg_.lr_pose_init, cfg_.lr_pose_final);
    st.raster_backward_ms = lap();
    ExponentialDecay sched{cfg_.lr_means_init * extent_, cfg_.lr_means_final * extent_, cfg_.iterations};
    adam_->set_lr(means_group_, float(sched(step_)));
    if (density_) density_stats_->accumulate(cmd_, raster_.grad2d_norm(), *params_, view.camera, 0.5f * view.camera.width);
    adam_->step(cmd_);
    cmd_.submit();
    st.optimizer_ms = lap();
    if (density_) {
      const DensityConfig& d = density_->config();
      if (d.refine_at(step_)) density_->refine(cmd_, *params_, *grads_, *adam_, *density_stats_, float(extent_), d.prune_big_at(step_));
      if (d.reset_at(step_)) {
        density_->reset_opacity(cmd_, *params_, *adam_);
        cmd_.submit();
      }
    }
  }
  st.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

Rasterizer& Trainer::frame_raster(uint32_t i) {
  if (i == 0) return raster_;
  while (frame_raster_.size() < i) {
    frame_raster_.push_back(std::make_unique<Rasterizer>(ctx_));
    frame_raster_.back()->borrow_backward_scratch(raster_);  // the frames' backward passes run in turn
  }
  return *frame_raster_[i - 1];
}

// Adam on one view's camera parameters (54 trajectory knots or a 6-vector pose delta), on the
// host (a few hundred flops), learning rate decaying exponentially over the run.
void Trainer::camera_adam(uint32_t v, const double* grad, double lr_init, double lr_final) {
  TrajectoryState& st = trajectory_state_[v];
  ExponentialDecay sched{lr_init, lr_final, cfg_.iterations};
  double* x = trajectories_.empty() ? pose_deltas_[v].data() : trajectories_[v].data();
  host_adam_step(x, grad, st.exp_avg.data(), st.exp_avg_sq.data(), st.exp_avg.size(), ++st.step, sched(step_));
}

// Time reversal of a view's trajectory: T'(u) = T(1 - u) up to the order of the factors (exact
// for commuting knots, close for exposure-sized motions): knot k takes knot 8 - k, and so do its
// Adam moments.
void Trainer::flip_trajectory(uint32_t v) {
  double* k = trajectories_[v].data();
  TrajectoryState& st = trajectory_state_[v];
  const int K = ExposureTrajectory::kKnots, D = ExposureTrajectory::kDof;
  for (int j = 0; j < K / 2; ++j)
    for (int c = 0; c < D; ++c) {
      std::swap(k[j * D + c], k[(K - 1 - j) * D + c]);
      std::swap(st.exp_avg[j * D + c], st.exp_avg[(K - 1 - j) * D + c]);
      std::swap(st.exp_avg_sq[j * D + c], st.exp_avg_sq[(K - 1 - j) * D + c]);
    }
  ++flips_;
}

std::vector<float> Trainer::render(const Camera& cam) {
  RenderSettings s;
  s.background = cfg_.background;
  s.antialiased = cfg_.antialiased;
  raster_.forward(*params_, cam, s);
  return raster_.outputs().rgb.read<float>(size_t(cam.width) * cam.height * 3);
}

}  // namespace evflow
