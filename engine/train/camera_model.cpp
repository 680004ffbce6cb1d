#include "train/camera_model.h"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include "optim/host_adam.h"
#include "optim/schedule.h"

namespace evflow {

static CameraModel::Kind kind_of(const TrainConfig& cfg) {
  if (cfg.mode == TrainMode::Blur) return CameraModel::Kind::Trajectory;
  return cfg.pose_refine ? CameraModel::Kind::PoseRefine : CameraModel::Kind::Fixed;
}

CameraModel::CameraModel(const io::Dataset& data, const TrainConfig& cfg)
    : data_(data),
      kind_(kind_of(cfg)),
      iterations_(cfg.iterations),
      warmup_steps_(cfg.edi_warmup_steps()),
      keep_mid_(cfg.edi_keep_mid && kind_ == Kind::Trajectory && warmup_steps_ > 0),
      mid_lr_(keep_mid_ ? cfg.edi_mid_lr : 0.0),
      knots_from_(cfg.edi_motion_steps() > 0 ? 0 : warmup_steps_),  // < iterations (check_edi_warmup)
      lr_pose_init_(cfg.lr_pose_init),
      lr_pose_final_(cfg.lr_pose_final) {
  const size_t nv = data.train.size();
  if (kind_ == Kind::Trajectory) {
    times_ = ExposureTrajectory::virtual_times(int(cfg.virtual_frames));
    lr_init_ = cfg.lr_trajectory_init, lr_final_ = cfg.lr_trajectory_final;
    for (size_t v = 0; v < nv; ++v)
      trajectories_.emplace_back(data.train[v].camera, cfg.seed * 100003 + v, cfg.trajectory_init_sigma);
  } else {
    times_ = {0.5};
    lr_init_ = cfg.lr_pose_init, lr_final_ = cfg.lr_pose_final;
    if (kind_ == Kind::PoseRefine) deltas_.assign(nv, lie::Vec6{});
  }
  const size_t dof = kind_ == Kind::Trajectory ? ExposureTrajectory::kSize : 6;
  if (kind_ != Kind::Fixed) adam_.assign(nv, {0, {}, std::vector<double>(dof, 0.0), std::vector<double>(dof, 0.0)});
  for (TrajectoryState& a : adam_) fresh_mid_moments(a);
}

Camera CameraModel::frame_camera(uint32_t view, uint32_t frame) const {
  if (kind_ == Kind::Trajectory) return trajectories_[view].camera_at(times_[frame]);
  return training_camera(view);
}

Camera CameraModel::training_camera(uint32_t v) const {
  switch (kind_) {
    case Kind::Trajectory:
      return trajectories_.at(v).camera_at(0.5);
    case Kind::PoseRefine:
      return data_.train.at(v).camera.perturbed(deltas_.at(v));
    case Kind::Fixed:
      break;
  }
  return data_.train.at(v).camera;
}

double* CameraModel::params(uint32_t v) {
  return kind_ == Kind::Trajectory ? trajectories_[v].data() : deltas_[v].data();
}
const double* CameraModel::params(uint32_t v) const {
  return kind_ == Kind::Trajectory ? trajectories_[v].data() : deltas_[v].data();
}

void CameraModel::backward_and_step(uint32_t view, const std::vector<lie::Vec6>& g, uint32_t step) {
  if (kind_ == Kind::Fixed) return;
  if (kind_ == Kind::Trajectory) {
    std::array<double, ExposureTrajectory::kSize> knot_grad{};
    for (size_t i = 0; i < g.size(); ++i) {
      const auto kg = trajectories_[view].backward(times_[i], g[i]);
      for (size_t k = 0; k < kg.size(); ++k) knot_grad[k] += kg[k];
    }
    last_grad_.assign(knot_grad.begin(), knot_grad.end());
    if (keep_mid_ && step > warmup_steps_) {
      const lie::Vec6 mid_grad = without_mid_move(last_grad_.data());
      const lie::SE3 mid = moved_mid(view, mid_grad, step);
      adam_step(view, rate(step));
      keep_mid(view, mid);
      return;
    }
  } else {
    // c2w Exp(delta) Exp(g-step) = c2w Exp(delta + J_r(delta)^-1 g-step): dL/ddelta = J_r(delta)^T g.
    const lie::Vec6 d = lie::mul_transposed(lie::se3_right_jacobian(deltas_[view]), g.back());
    last_grad_.assign(d.begin(), d.end());
  }
  adam_step(view, rate(step));
}

// The parameters' rate at `step`. After an EDI warm-up that learned no motion (of the
// mid-exposure frame alone) the knots' schedule runs over the blur steps; otherwise over the run.
double CameraModel::rate(uint32_t step) const {
  const ExponentialDecay sched{lr_init_, lr_final_, iterations_ - knots_from_};
  return sched(step > knots_from_ ? step - knots_from_ : 0);
}

void CameraModel::frame_step(uint32_t view, uint32_t frame, const lie::Vec6& g, uint32_t step) {
  if (kind_ != Kind::Trajectory) throw std::logic_error("CameraModel::frame_step: only trajectories have knots");
  const auto kg = trajectories_[view].backward(times_.at(frame), g);
  last_grad_.assign(kg.begin(), kg.end());
  adam_step(view, rate(step));
}

void CameraModel::shift_and_step(uint32_t view, const lie::Vec6& g, uint32_t step) {
  if (kind_ != Kind::Trajectory) throw std::logic_error("CameraModel::shift_and_step: only trajectories have knots");
  const auto kg = trajectories_[view].backward(0.5, g);
  std::array<double, ExposureTrajectory::kDof> sum{};
  for (size_t k = 0; k < kg.size(); ++k) sum[k % sum.size()] += kg[k];
  last_grad_.resize(kg.size());
  for (size_t k = 0; k < kg.size(); ++k) last_grad_[k] = sum[k % sum.size()];
  const ExponentialDecay sched{lr_pose_init_, lr_pose_final_, std::max(warmup_steps_, 1u)};
  adam_step(view, sched(step));
}

// The warm-up's moments are the shift's: one gradient for every knot, small once the mid frames
// fit EDI. Against them the blur loss's first knot gradients, far larger and differing per knot,
// would take steps of several times the knots' rate for each view's first tens of visits.
void CameraModel::begin_step(uint32_t step) {
  if (kind_ != Kind::Trajectory || knots_from_ == 0 || step != knots_from_ + 1) return;
  for (TrajectoryState& a : adam_) {
    a.step = 0;
    std::fill(a.exp_avg.begin(), a.exp_avg.end(), 0.0);
    std::fill(a.exp_avg_sq.begin(), a.exp_avg_sq.end(), 0.0);
  }
}

void CameraModel::adam_step(uint32_t view, double lr) {
  TrajectoryState& a = adam_[view];
  host_adam_step(params(view), last_grad_.data(), a.exp_avg.data(), a.exp_avg_sq.data(), a.exp_avg.size(), ++a.step,
                 lr);
}

// Removes from a knot gradient, component by component, its part along the Bernstein weights at
// u = 0.5: to first order the part that moves T(0.5). Adam's moments then hold the motion's
// gradient alone; with the mid-exposure pose's part in them, which keep_mid undoes at every step,
// its normalised steps would shrink the motion's and the motions go wrong (experiments.md).
// Returns the removed part's size per component: moving the knots by s b_j moves T(0.5) by about
// Exp(s |b|^2) on the right, so it is the loss's gradient for a right move of T(0.5), up to the
// factor |b|^2 that Adam does not see.
lie::Vec6 CameraModel::without_mid_move(double* grad) {
  const auto b = ExposureTrajectory::bernstein_weights(0.5);
  double bb = 0;
  for (double x : b) bb += x * x;
  lie::Vec6 along{};
  for (int c = 0; c < ExposureTrajectory::kDof; ++c) {
    double& bg = along[c];
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) bg += b[j] * grad[j * ExposureTrajectory::kDof + c];
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) grad[j * ExposureTrajectory::kDof + c] -= b[j] * bg / bb;
  }
  return along;
}

// The mid-exposure pose this blur step keeps: the one before it, or (edi_mid_lr > 0) that pose
// moved on the right by one step of its own Adam on `mid_grad`, at edi_mid_lr decayed as the
// knots' rate is. Slow and smooth, so that a view the warm-up left a pixel off can still settle
// while the first, sign-like steps of fresh moments cannot throw a view into a neighbouring basin
// of the blur loss (experiments.md).
lie::SE3 CameraModel::moved_mid(uint32_t view, const lie::Vec6& mid_grad, uint32_t step) {
  const lie::SE3 mid = trajectories_[view].offset(0.5);
  if (mid_lr_ <= 0) return mid;
  TrajectoryState& a = adam_[view];
  lie::Vec6 move{};
  host_adam_step(move.data(), mid_grad.data(), a.mid_exp_avg.data(), a.mid_exp_avg_sq.data(), move.size(), ++a.mid_step,
                 mid_lr_ * rate(step) / lr_init_);
  return mid * lie::se3_exp(move);
}

// The mid pose's Adam state before its first step: six zero moments each with edi_mid_lr, none
// without.
void CameraModel::fresh_mid_moments(TrajectoryState& a) const {
  a.mid_step = 0;
  a.mid_exp_avg = a.mid_exp_avg_sq = std::vector<double>(mid_lr_ > 0 ? 6 : 0, 0.0);
}

// Adds one se(3) vector c to every knot so that T(0.5) is `mid` again. Adding c to each knot moves
// T(0.5) by about Exp(c) on the right (the Bernstein weights sum to one; exact for commuting
// knots), so c is refined by the remaining right-hand error: each pass shrinks the error by about
// the knots' size (1e-2 for exposure-sized motions), so a few passes reach rounding.
void CameraModel::keep_mid(uint32_t view, const lie::SE3& mid) {
  ExposureTrajectory& tr = trajectories_[view];
  for (int pass = 0; pass < 12; ++pass) {
    const lie::Vec6 c = lie::se3_log(tr.offset(0.5).inverse() * mid);
    double size = 0;
    for (int k = 0; k < ExposureTrajectory::kDof; ++k) {
      size = std::max(size, std::abs(c[k]));
      for (int j = 0; j < ExposureTrajectory::kKnots; ++j) tr.data()[j * ExposureTrajectory::kDof + k] += c[k];
    }
    if (size < 1e-15) return;
  }
}

// T'(u) = T(1 - u) up to the order of the factors (exact for commuting knots, close for
// exposure-sized motions): knot k takes knot 8 - k, and so do its Adam moments.
void CameraModel::flip(uint32_t v) {
  if (kind_ != Kind::Trajectory) throw std::logic_error("CameraModel::flip: only trajectories have a time direction");
  double* k = trajectories_[v].data();
  TrajectoryState& a = adam_[v];
  const int K = ExposureTrajectory::kKnots, D = ExposureTrajectory::kDof;
  for (int j = 0; j < K / 2; ++j)
    for (int c = 0; c < D; ++c) {
      std::swap(k[j * D + c], k[(K - 1 - j) * D + c]);
      std::swap(a.exp_avg[j * D + c], a.exp_avg[(K - 1 - j) * D + c]);
      std::swap(a.exp_avg_sq[j * D + c], a.exp_avg_sq[(K - 1 - j) * D + c]);
    }
}

std::vector<TrajectoryState> CameraModel::state() const {
  std::vector<TrajectoryState> out = adam_;
  for (uint32_t v = 0; v < out.size(); ++v) {
    const double* p = params(v);
    out[v].knots.assign(p, p + out[v].exp_avg.size());
  }
  return out;
}

void CameraModel::load(const std::vector<TrajectoryState>& saved, const TrainConfig& cfg) {
  if (saved.empty()) return;
  const size_t want = adam_.size(), dof = kind_ == Kind::Trajectory ? ExposureTrajectory::kSize : 6;
  if (saved.size() != want || saved[0].knots.size() != dof)
    throw std::invalid_argument("checkpoint has " + std::to_string(saved.size()) + " camera states of " +
                                std::to_string(saved[0].knots.size()) + " values; this run (mode " +
                                std::string(mode_name(cfg.mode)) + (cfg.pose_refine ? ", pose_refine" : "") + ") has " +
                                std::to_string(want) + " of " + std::to_string(dof));
  // The mid pose's moments: kept when this run moves the mid pose and they were saved; fresh when
  // it moves it and they were not (a checkpoint of a run without edi_mid_lr); dropped otherwise.
  for (uint32_t v = 0; v < want; ++v) {
    std::copy(saved[v].knots.begin(), saved[v].knots.end(), params(v));
    TrajectoryState a = saved[v];
    if (mid_lr_ <= 0 || a.mid_exp_avg.size() != 6) fresh_mid_moments(a);
    adam_[v] = std::move(a);
  }
}

}  // namespace evflow
