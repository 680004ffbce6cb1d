// The training views' cameras as the model learns them, one kind per run:
//   Fixed        the dataset's poses (plain mode);
//   PoseRefine   a per-view se(3) delta, c2w' = c2w Exp(delta) (plain mode, pose_refine);
//   Trajectory   a Bézier SE(3) exposure trajectory per view (blur mode, paper Sec. 4.1).
// It gives each step's frame cameras, maps the frames' pose gradients to its parameters, and
// runs their Adam on the host (a few hundred flops per step).
#pragma once
#include <cstdint>
#include <vector>

#include "camera/se3.h"
#include "camera/trajectory.h"
#include "io/dataset.h"
#include "train/checkpoint.h"
#include "train/train_config.h"

namespace evflow {

class CameraModel {
 public:
  enum class Kind { Fixed, PoseRefine, Trajectory };
  CameraModel(const io::Dataset& data, const TrainConfig& cfg);

  Kind kind() const { return kind_; }
  // The exposure times u in [0, 1] of a step's frames: 2N+1 virtual frames, or {0.5}.
  const std::vector<double>& frame_times() const { return times_; }
  Camera frame_camera(uint32_t view, uint32_t frame) const;
  // The camera the model currently believes view v was taken from (mid-exposure).
  Camera training_camera(uint32_t view) const;
  const std::vector<ExposureTrajectory>& trajectories() const { return trajectories_; }

  // The frames' pose gradients (se(3), translation first, one per frame in frame order) to the
  // view's parameters; one Adam step on them at training step `step`. No-op for Fixed. With
  // edi_keep_mid, a blur step after the EDI warm-up steps only the motion: the gradient's part
  // that would move the mid-exposure pose is removed before Adam (without_mid_move), and all knots
  // are shifted alike after it so that T(0.5) is exactly the pose before the step (keep_mid); with
  // edi_mid_lr > 0, the pose before the step moved by its own Adam on the removed part.
  void backward_and_step(uint32_t view, const std::vector<lie::Vec6>& frame_pose_grads, uint32_t step);
  // EDI warm-up (Trajectory only): frame u = 0.5's pose gradient applied to every knot alike, so
  // the trajectory shifts as a whole and keeps its shape (one frame says nothing about the
  // motion); one Adam step at the pose refinement's rate (lr_pose_init -> lr_pose_final over
  // the warm-up).
  void shift_and_step(uint32_t view, const lie::Vec6& mid_pose_grad, uint32_t step);
  // EDI warm-up's virtual-frame steps (edi_warmup_motion; Trajectory only): one frame's pose
  // gradient to every knot through the trajectory at the frame's time; one Adam step on the
  // knots' schedule.
  void frame_step(uint32_t view, uint32_t frame, const lie::Vec6& frame_pose_grad, uint32_t step);
  // Called at the start of every training step. At the first blur step after a warm-up that
  // only shifted the trajectories, the knots' Adam moments start afresh (training.md, "EDI
  // warm-up").
  void begin_step(uint32_t step);
  // What the last backward_and_step applied before Adam (54 knot or 6 delta values; empty for Fixed).
  const std::vector<double>& last_gradient() const { return last_grad_; }
  // Time reversal of a view's trajectory, with its Adam moments (Trajectory only).
  void flip(uint32_t view);

  // Per view: parameters and Adam state (empty for Fixed).
  std::vector<TrajectoryState> state() const;
  // Throws naming both shapes when `saved` does not fit this run.
  void load(const std::vector<TrajectoryState>& saved, const TrainConfig& cfg);

 private:
  void adam_step(uint32_t view, double lr);
  static lie::Vec6 without_mid_move(double* knot_grad);
  lie::SE3 moved_mid(uint32_t view, const lie::Vec6& mid_grad, uint32_t step);
  void fresh_mid_moments(TrajectoryState& a) const;
  void keep_mid(uint32_t view, const lie::SE3& mid);
  double rate(uint32_t step) const;
  double* params(uint32_t view);
  const double* params(uint32_t view) const;
  const io::Dataset& data_;
  Kind kind_;
  std::vector<double> times_;
  uint32_t iterations_;
  uint32_t warmup_steps_;
  bool keep_mid_;        // edi_keep_mid: blur steps after the warm-up keep T(0.5)
  double mid_lr_;        // edi_mid_lr: or move it by its own Adam, from this rate on the knots' decay
  uint32_t knots_from_;  // the knots' schedule starts here, where the motion is first learned
  double lr_init_ = 0, lr_final_ = 0;
  double lr_pose_init_, lr_pose_final_;  // the warm-up's shifts
  std::vector<ExposureTrajectory> trajectories_;
  std::vector<lie::Vec6> deltas_;
  std::vector<TrajectoryState> adam_;  // knots unused here: the parameters live above
  std::vector<double> last_grad_;
};

}  // namespace evflow
