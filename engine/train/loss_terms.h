// The training loss as a list of terms, kept by kind as they are added:
//   image terms     compare the image model's prediction with the view's target;
//   exposure terms  see every virtual frame of the exposure (the event loss; flow and
//                   residual terms plug in here);
//   branch terms    recorded by a branch with its own parameters (LdiBranch), only read here.
// Values are read back in the order the terms were added (the order of curve.csv's columns), from
// one buffer that every term added writes its values into: one download per step for all.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "loss/loss_term.h"
#include "train/image_model.h"

namespace evflow {

struct LossValues {
  std::vector<double> terms;            // unweighted, in the order added; 0 for a term not recorded this step
  double total = 0;                     // sum of weight * value
  const LossTerm* first_bad = nullptr;  // the first term whose value is not finite
};

class LossTerms {
 public:
  void add(std::unique_ptr<ImageLossTerm> term);
  void add(std::unique_ptr<ExposureLossTerm> term);
  // A term its branch records every step (writing 0 when it is off that step); with `scheduled`
  // it counts in the total with the event terms' schedule, as the exposure terms.
  void add_branch_term(LossTerm* term, bool scheduled);
  const std::vector<LossTerm*>& all() const { return all_; }
  bool has_exposure_terms() const { return !exposure_.empty(); }

  // Image terms: d(loss)/d(prediction) into image_model.prediction_grad(), each frame's share
  // (1/mean_count of it) already applied.
  void record_image_terms(gpu::Commands& cmd, const ImageModel& image_model, const gpu::Buffer& target) const;
  // Exposure terms add their per-frame gradients into frames.grad, each with its weight times
  // `scale` (the run's schedule of the event terms; the weights themselves stay as set). With
  // frames.grad_in, the gradients start from it: the first term reads it where it folds, else it
  // is copied into grad first. With frames.render_grad, returns true when the last term wrote
  // the renders' gradients there (it folds), false when grad holds the frames' gradients.
  bool record_exposure_terms(gpu::Commands& cmd, const ExposureFrames& frames, double scale = 1.0) const;
  // After the submit: every term's value (exposure terms only when `exposure_recorded`, counted
  // in the total with their weight times `exposure_scale`; branch terms only when
  // `branches_recorded`). A term not recorded reads 0.
  LossValues read(bool exposure_recorded, bool branches_recorded, double exposure_scale = 1.0) const;

 private:
  std::vector<std::unique_ptr<ImageLossTerm>> image_;
  std::vector<std::unique_ptr<ExposureLossTerm>> exposure_;
  std::vector<LossTerm*> all_;
  // Gives `term` its slot in values_ (grown as terms are added, before any is recorded).
  void share_values(LossTerm& term);
  std::unique_ptr<gpu::Buffer> values_;
  uint32_t value_floats_ = 0;  // the slots given so far
  enum class Kind { Image, Exposure, Branch, ScheduledBranch };
  std::vector<Kind> kind_;  // per entry of all_
};

}  // namespace evflow
