#include "train/loss_terms.h"

#include <cmath>

namespace evflow {

void LossTerms::share_values(LossTerm& term) {
  if (!values_) values_ = std::make_unique<gpu::Buffer>(term.value_buffer().context(), 256, "loss_values");
  const uint32_t first = value_floats_;
  value_floats_ += term.value_count();
  values_->ensure(uint64_t(value_floats_) * 4);
  term.set_value_slot(*values_, first);
}

void LossTerms::add(std::unique_ptr<ImageLossTerm> term) {
  share_values(*term);
  all_.push_back(term.get());
  kind_.push_back(Kind::Image);
  image_.push_back(std::move(term));
}

void LossTerms::add(std::unique_ptr<ExposureLossTerm> term) {
  share_values(*term);
  all_.push_back(term.get());
  kind_.push_back(Kind::Exposure);
  exposure_.push_back(std::move(term));
}

void LossTerms::add_branch_term(LossTerm* term, bool scheduled) {
  share_values(*term);
  all_.push_back(term);
  kind_.push_back(scheduled ? Kind::ScheduledBranch : Kind::Branch);
}

void LossTerms::record_image_terms(gpu::Commands& cmd, const ImageModel& m, const gpu::Buffer& target) const {
  bool first = true;
  for (auto& t : image_) {
    t->record(cmd, m.prediction(), target, m.prediction_grad(), t->weight() / float(m.mean_count()), !first);
    cmd.mark(t->name());
    first = false;
  }
}

void LossTerms::record_exposure_terms(gpu::Commands& cmd, const ExposureFrames& frames, double scale) const {
  for (auto& t : exposure_) {
    t->record(cmd, frames, float(t->weight() * scale));
    cmd.mark(t->name());
  }
}

LossValues LossTerms::read(bool exposure_recorded, bool branches_recorded, double exposure_scale) const {
  LossValues out;
  const std::vector<float> values = values_ ? values_->read<float>(value_floats_) : std::vector<float>();
  for (size_t i = 0; i < all_.size(); ++i) {
    const bool branch = kind_[i] == Kind::Branch || kind_[i] == Kind::ScheduledBranch;
    if ((kind_[i] == Kind::Exposure && !exposure_recorded) || (branch && !branches_recorded)) {
      out.terms.push_back(0.0);
      continue;
    }
    const double v = values[all_[i]->value_offset()];
    out.terms.push_back(v);
    const bool scheduled = kind_[i] == Kind::Exposure || kind_[i] == Kind::ScheduledBranch;
    out.total += all_[i]->weight() * (scheduled ? exposure_scale : 1.0) * v;
    if (!std::isfinite(v) && !out.first_bad) out.first_bad = all_[i];
  }
  return out;
}

}  // namespace evflow
