// Line charts on a Raster: an axis with round tick values, and a framed panel with a title,
// tick labels, a legend and one polyline per series.
#pragma once
#include <string>
#include <vector>

#include "plot/raster.h"

namespace evflow::plot {

// A value range with ticks at round numbers (1, 2 or 5 times a power of ten).
struct Axis {
  double lo = 0, hi = 1;
  std::vector<double> ticks;
};
// The range [lo, hi] widened to the ticks around it, at most about `max_ticks` of them; a range
// of zero width is widened around its value. Throws on non-finite bounds.
Axis nice_axis(double lo, double hi, int max_ticks);
// A tick label: up to 4 significant digits, no trailing zeros ("0.05", "1500", "2.5E-05").
std::string tick_label(double v);

struct Series {
  std::string name;
  std::vector<double> x, y;  // non-finite points break the line
  Rgb colour;
};

// Where a chart's plot area lies: the pixels (left..right, top..bottom, inclusive) inside the frame.
struct PlotArea {
  int left = 0, top = 0, right = 0, bottom = 0;
  Axis x, y;
  int px(double v) const;  // the column of x value v (rounded)
  int py(double v) const;  // the row of y value v (rounded; larger values higher up)
};

// Draws a chart into the box (x0, y0)-(x1, y1) of `r`: the title and the legend above, y tick
// labels on the left, x tick labels below, grid lines at the ticks, then the series. The y axis
// spans the series' finite values; returns the plot area.
PlotArea draw_chart(Raster& r, int x0, int y0, int x1, int y1, const std::string& title, const Axis& x,
                    const std::vector<Series>& series);

}  // namespace evflow::plot
