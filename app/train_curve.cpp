#include "train_curve.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "metrics/srgb_metrics.h"
#include "plot/curve_plot.h"

namespace evflow::app {

namespace fs = std::filesystem;

static std::string first_line(const fs::path& p) {
  std::ifstream f(p);
  std::string line;
  std::getline(f, line);
  return line;
}

TrainCurve::TrainCurve(const fs::path& run, const Trainer& trainer, bool resume)
    : csv_(run / "curve.csv"), png_(run / "curve.png") {
  std::string columns = "step,view,loss,ms,flipped";
  for (auto& t : trainer.losses()) columns += "," + t->name();
  if (resume && fs::exists(csv_)) {
    const std::string header = first_line(csv_);
    has_psnr_ = header.size() >= 5 && header.compare(header.size() - 5, 5, ",psnr") == 0;
    const std::string terms = has_psnr_ ? header.substr(0, header.size() - 5) : header;
    if (terms != columns)
      throw std::runtime_error(csv_.string() + ": its columns (" + terms + ") are not this run's loss terms (" +
                               columns +
                               "): continue with the keys the run started with (its config.json), or "
                               "train into a new folder");
    out_.open(csv_, std::ios::app);
  } else {
    out_.open(csv_, std::ios::trunc);
    out_ << columns << ",psnr\n";
  }
  if (!out_) throw std::runtime_error(csv_.string() + ": cannot open for writing");
}

double TrainCurve::add(Trainer& trainer, const StepStats& st, bool with_psnr) {
  const double psnr = with_psnr ? training_psnr(trainer, st.view) : std::numeric_limits<double>::quiet_NaN();
  out_ << st.step << "," << st.view << "," << st.loss << "," << st.ms << "," << (st.flipped ? 1 : 0);
  for (double v : st.term_values) out_ << "," << v;
  if (has_psnr_) out_ << ",";
  if (has_psnr_ && std::isfinite(psnr)) out_ << psnr;
  out_ << "\n";
  return psnr;
}

void TrainCurve::flush() {
  out_.flush();
  if (!out_) throw std::runtime_error(csv_.string() + ": write failed");
}

void TrainCurve::plot() {
  flush();
  plot::write_curve_png(csv_, png_);
}

double training_psnr(Trainer& trainer, uint32_t v) {
  const ViewSnapshot snap = trainer.snapshot(v);
  return metrics::psnr_srgb(snap.model, snap.target);
}

}  // namespace evflow::app
