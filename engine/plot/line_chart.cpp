#include "plot/line_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace evflow::plot {

namespace {

const Rgb kInk{40, 40, 40}, kFrame{120, 120, 120}, kGrid{225, 225, 225};
constexpr int kTickLen = 4;

// The smallest round step (1, 2 or 5 times a power of ten) that spans `range` in <= max_ticks steps.
double round_step(double range, int max_ticks) {
  const double raw = range / std::max(1, max_ticks);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

}  // namespace

Axis nice_axis(double lo, double hi, int max_ticks) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) throw std::invalid_argument("plot axis: non-finite range");
  if (hi < lo) std::swap(lo, hi);
  if (hi - lo <= 1e-12 * std::max(1.0, std::abs(hi))) {  // a constant: one unit (or 10 %) around it
    const double pad = lo == 0 ? 1.0 : std::abs(lo) * 0.1;
    lo -= pad;
    hi += pad;
  }
  const double step = round_step(hi - lo, max_ticks);
  Axis a;
  a.lo = std::floor(lo / step) * step;
  a.hi = std::ceil(hi / step) * step;
  for (long k = std::lround(a.lo / step); k <= std::lround(a.hi / step); ++k) a.ticks.push_back(double(k) * step);
  return a;
}

std::string tick_label(double v) {
  if (std::abs(v) < 1e-300) return "0";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4G", v);
  return buf;
}

int PlotArea::px(double v) const { return left + int(std::lround((v - x.lo) / (x.hi - x.lo) * (right - left))); }
int PlotArea::py(double v) const { return bottom - int(std::lround((v - y.lo) / (y.hi - y.lo) * (bottom - top))); }

static Axis y_axis_of(const std::vector<Series>& series) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series)
    for (double v : s.y)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!std::isfinite(lo)) lo = 0, hi = 1;  // nothing to draw: an empty unit range
  return nice_axis(lo, hi, 5);
}

static void draw_polyline(Raster& r, const PlotArea& a, const Series& s) {
  bool have_prev = false;
  int px0 = 0, py0 = 0;
  for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
      have_prev = false;
      continue;
    }
    const int px = a.px(s.x[i]), py = a.py(s.y[i]);
    if (have_prev)
      r.line(px0, py0, px, py, s.colour);
    else
      r.set(px, py, s.colour);
    px0 = px, py0 = py, have_prev = true;
  }
}

static void draw_axes(Raster& r, const PlotArea& a) {
  for (double t : a.y.ticks) {
    const int y = a.py(t);
    r.line(a.left, y, a.right, y, kGrid);
    r.line(a.left - kTickLen, y, a.left - 1, y, kFrame);
    const std::string s = tick_label(t);
    r.text(a.left - kTickLen - 2 - Raster::text_width(s), y - Raster::kCellH / 2, s, kInk);
  }
  for (double t : a.x.ticks) {
    const int x = a.px(t);
    r.line(x, a.top, x, a.bottom, kGrid);
    r.line(x, a.bottom + 1, x, a.bottom + kTickLen, kFrame);
    const std::string s = tick_label(t);
    r.text(x - Raster::text_width(s) / 2, a.bottom + kTickLen + 2, s, kInk);
  }
  r.line(a.left - 1, a.top - 1, a.right + 1, a.top - 1, kFrame);
  r.line(a.left - 1, a.bottom + 1, a.right + 1, a.bottom + 1, kFrame);
  r.line(a.left - 1, a.top - 1, a.left - 1, a.bottom + 1, kFrame);
  r.line(a.right + 1, a.top - 1, a.right + 1, a.bottom + 1, kFrame);
}

PlotArea draw_chart(Raster& r, int x0, int y0, int x1, int y1, const std::string& title, const Axis& x,
                    const std::vector<Series>& series) {
  PlotArea a;
  a.x = x;
  a.y = y_axis_of(series);
  int label_w = 0;
  for (double t : a.y.ticks) label_w = std::max(label_w, Raster::text_width(tick_label(t)));
  a.left = x0 + label_w + kTickLen + 4;
  a.right = x1 - Raster::text_width(tick_label(x.hi)) / 2 - 2;
  a.top = y0 + Raster::kCellH + 6;
  a.bottom = y1 - Raster::kCellH - kTickLen - 4;
  if (a.right - a.left < 8 || a.bottom - a.top < 8) throw std::invalid_argument("plot: chart box too small");
  draw_axes(r, a);
  r.text(a.left, y0 + 2, title, kInk);
  int lx = a.left + Raster::text_width(title) + 3 * Raster::kCellW;
  for (const auto& s : series) {
    if (series.size() > 1) {  // a legend: a colour swatch and the name
      r.fill_rect(lx, y0 + 4, lx + 10, y0 + 6, s.colour);
      r.text(lx + 14, y0 + 2, s.name, kInk);
      lx += 14 + Raster::text_width(s.name) + 2 * Raster::kCellW;
    }
  }
  for (const auto& s : series) draw_polyline(r, a, s);
  return a;
}

}  // namespace evflow::plot
