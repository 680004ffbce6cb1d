#include "plot/curve_plot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace evflow::plot {

namespace {

constexpr int kChartH = 170;
const Rgb kBackground{255, 255, 255};
// Line colours, one per chart in turn.
const Rgb kColours[] = {{31, 100, 180}, {214, 90, 20}, {40, 150, 60}, {170, 40, 160}, {200, 40, 40}, {90, 90, 90}};

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

double parse_cell(const std::string& cell, const std::filesystem::path& path, size_t line_no, const std::string& col) {
  if (cell.empty()) return std::numeric_limits<double>::quiet_NaN();
  try {
    size_t pos = 0;
    const double v = std::stod(cell, &pos);
    if (pos == cell.size()) return v;
  } catch (const std::exception&) {}
  throw std::runtime_error(path.string() + ":" + std::to_string(line_no) + ": column '" + col + "' holds '" + cell +
                           "', not a number");
}

}  // namespace

int CurveTable::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  return it == columns.end() ? -1 : int(it - columns.begin());
}

CurveTable read_curve_csv(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path.string() + ": cannot open the curve file");
  CurveTable t;
  std::string line;
  if (!std::getline(f, line) || line.empty()) throw std::runtime_error(path.string() + ": no header line");
  t.columns = split_csv_line(line);
  for (size_t line_no = 2; std::getline(f, line); ++line_no) {
    if (line.empty()) continue;
    const auto cells = split_csv_line(line);
    if (cells.size() != t.columns.size())
      throw std::runtime_error(path.string() + ":" + std::to_string(line_no) + ": " + std::to_string(cells.size()) +
                               " cells, the header has " + std::to_string(t.columns.size()));
    std::vector<double> row;
    for (size_t c = 0; c < cells.size(); ++c) row.push_back(parse_cell(cells[c], path, line_no, t.columns[c]));
    t.rows.push_back(std::move(row));
  }
  return t;
}

std::vector<std::string> plotted_columns(const CurveTable& t) {
  std::vector<std::string> out;
  for (const auto& c : t.columns)
    if (c != "step" && c != "view" && c != "ms" && c != "flipped") out.push_back(c);
  return out;
}

CurveFigure plot_curve(const CurveTable& t, int width) {
  const int step_col = t.column("step");
  if (step_col < 0) throw std::invalid_argument("curve plot: the table has no 'step' column");
  const auto names = plotted_columns(t);
  if (names.empty()) throw std::invalid_argument("curve plot: the table has no column to draw");
  std::vector<double> steps;
  for (const auto& row : t.rows) steps.push_back(row[size_t(step_col)]);
  double lo = 0, hi = 1;
  for (double s : steps)
    if (std::isfinite(s)) hi = std::max(hi, s);
  const Axis x = nice_axis(lo, hi, 8);
  CurveFigure fig{Raster(width, int(names.size()) * kChartH, kBackground), names, {}};
  for (size_t k = 0; k < names.size(); ++k) {
    // Empty cells (not measured that step, e.g. the PSNR between log steps) are left out: the
    // line joins the measured points.
    Series s{names[k], {}, {}, kColours[k % std::size(kColours)]};
    const size_t col = size_t(t.column(names[k]));
    for (size_t r = 0; r < t.rows.size(); ++r)
      if (std::isfinite(t.rows[r][col]) && std::isfinite(steps[r])) {
        s.x.push_back(steps[r]);
        s.y.push_back(t.rows[r][col]);
      }
    const std::string title = names[k] == "psnr"   ? "PSNR in dB (training view)"
                              : names[k] == "loss" ? "loss (weighted total)"
                                                   : names[k] + " (unweighted)";
    const int y0 = int(k) * kChartH;
    fig.areas.push_back(draw_chart(fig.image, 4, y0, width - 6, y0 + kChartH - 1, title + " against step", x, {s}));
  }
  return fig;
}

void write_curve_png(const std::filesystem::path& csv, const std::filesystem::path& png) {
  plot_curve(read_curve_csv(csv)).image.write_png(png);
}

}  // namespace evflow::plot
