// RUN/curve.csv and RUN/curve.png of `evflow train`: a row per step (the weighted total loss, the
// step's time, each loss term's unweighted value) and, every log_every steps and at the last
// one, the training PSNR; the figure is redrawn from the file with every checkpoint.
#pragma once
#include <filesystem>
#include <fstream>

#include "train/trainer.h"

namespace evflow::app {

class TrainCurve {
 public:
  // A fresh file, or with `resume` the run's file continued (a file from before the psnr column
  // goes on without it); throws naming the file when its loss columns are not the trainer's.
  TrainCurve(const std::filesystem::path& run, const Trainer& trainer, bool resume);
  // Appends the step's row; measures the PSNR (one extra render) when `with_psnr`. Returns it
  // (NaN when not measured).
  double add(Trainer& trainer, const StepStats& st, bool with_psnr);
  // Puts the rows written so far on the disk; throws naming the file when it cannot.
  void flush();
  // Writes RUN/curve.png from what the file holds so far.
  void plot();

 private:
  std::filesystem::path csv_, png_;
  std::ofstream out_;
  bool has_psnr_ = true;
};

// The training PSNR of view v: the image model's prediction against the view's training target
// (8-bit sRGB, as `evflow eval` scores), rendered as the next step would.
double training_psnr(Trainer& trainer, uint32_t v);

}  // namespace evflow::app
