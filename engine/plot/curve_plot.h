// curve.png: a training run's curve.csv drawn against the step, one chart per quantity (the
// weighted total loss, each loss term, the training PSNR when the file has it).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "plot/line_chart.h"
#include "plot/raster.h"

namespace evflow::plot {

// A CSV file of numbers with a header line; an empty cell reads as NaN (not measured that row).
struct CurveTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  // each as long as columns
  // The index of column `name`, or -1.
  int column(const std::string& name) const;
};
// Throws std::runtime_error naming the file (and line) on a missing file, a missing header, a
// row with the wrong number of cells or a cell that is not a number.
CurveTable read_curve_csv(const std::filesystem::path& path);

// The columns that are drawn: everything but the bookkeeping ones (step, view, ms, flipped).
std::vector<std::string> plotted_columns(const CurveTable& t);

struct CurveFigure {
  Raster image;
  std::vector<std::string> names;  // the chart of each plotted column, top to bottom
  std::vector<PlotArea> areas;
};
// The figure of `t` (needs a "step" column), `width` pixels wide.
CurveFigure plot_curve(const CurveTable& t, int width = 800);

// Reads `csv` and writes its figure to `png` (atomically).
void write_curve_png(const std::filesystem::path& csv, const std::filesystem::path& png);

}  // namespace evflow::plot
