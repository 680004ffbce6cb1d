#include "train/loss_terms.h"

#include <algorithm>
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

namespace {

void copy_grad_in(gpu::Commands& cmd, const ExposureFrames& f, size_t i) {
  cmd.copy(*f.grad_in.at(i), *f.grad[i], std::min(f.grad_in[i]->size(), f.grad[i]->size()));
}

}  // namespace

bool LossTerms::record_exposure_terms(gpu::Commands& cmd, const ExposureFrames& frames, double scale) const {
  ExposureFrames f = frames;
  bool rendered = false;
  for (size_t k = 0; k < exposure_.size(); ++k) {
    ExposureLossTerm& t = *exposure_[k];
    // The renders' gradients are the last term's to write, where it can.
    if (k + 1 < exposure_.size() || !t.folds(f)) f.render_grad.clear();
    if (!f.grad_in.empty() && !t.folds(f)) {  // the term adds into grad: start it from grad_in
      for (size_t i = 0; i < f.grad.size(); ++i) copy_grad_in(cmd, f, i);
      f.grad_in.clear();
    }
    t.record(cmd, f, float(t.weight() * scale));
    cmd.mark(t.name());
    f.grad_in.clear();  // from here on the frames' gradients are in grad
    rendered = !f.render_grad.empty();
  }
  if (!f.grad_in.empty())  // no exposure term: the gradients are the shares
    for (size_t i = 0; i < f.grad.size(); ++i) copy_grad_in(cmd, f, i);
  return rendered;
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
