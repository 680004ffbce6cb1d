// curve.png: the plot rasteriser draws the data where the axes say, and training writes the
// figure of its curve.csv (with the training PSNR) that `evflow plot` redraws.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.h"
#include "io/image.h"
#include "plot/bitmap_font.h"
#include "plot/curve_plot.h"

using namespace evflow;
using namespace evflow::plot;
namespace fs = std::filesystem;

namespace {

CurveTable table(std::vector<std::string> columns, std::vector<std::vector<double>> rows) {
  return CurveTable{std::move(columns), std::move(rows)};
}

// How many pixels of the plot area's row y have colour c.
int count_in_row(const Raster& r, const PlotArea& a, int y, Rgb c) {
  int n = 0;
  for (int x = a.left; x <= a.right; ++x) n += r.at(x, y) == c;
  return n;
}

}  // namespace

TEST_CASE("plot: a constant series is one horizontal line at its value, a rising one passes through its points",
          "[plot]") {
  std::vector<std::vector<double>> rows;
  for (int s = 1; s <= 40; ++s) rows.push_back({double(s), 0.25, 0.5 + 0.01 * s});
  const CurveFigure fig = plot_curve(table({"step", "loss", "events"}, rows), 600);
  REQUIRE(fig.names == std::vector<std::string>{"loss", "events"});
  REQUIRE(fig.areas.size() == 2);
  const PlotArea& c = fig.areas[0];
  const Rgb line = fig.image.at(c.px(20), c.py(0.25));
  CHECK(!(line == Rgb{255, 255, 255}));
  // The whole run from step 1 to 40 lies on the value's row, and the colour is nowhere else.
  const int y = c.py(0.25);
  CHECK(count_in_row(fig.image, c, y, line) == c.px(40) - c.px(1) + 1);
  int elsewhere = 0;
  for (int yy = c.top; yy <= c.bottom; ++yy)
    if (yy != y) elsewhere += count_in_row(fig.image, c, yy, line);
  CHECK(elsewhere == 0);
  // The y axis spans the constant: its ticks bracket 0.25.
  CHECK(c.y.lo < 0.25);
  CHECK(c.y.hi > 0.25);
  // The rising series: every data point is drawn in its colour, and each column of the line
  // between steps 1 and 40 has its lit pixels between the neighbouring points' rows.
  const PlotArea& e = fig.areas[1];
  const Rgb rise = fig.image.at(e.px(1), e.py(0.51));
  CHECK(!(rise == line));
  for (int s = 1; s <= 40; ++s) CHECK(fig.image.at(e.px(s), e.py(0.5 + 0.01 * s)) == rise);
  CHECK(e.py(0.9) < e.py(0.51));  // larger values higher up
  for (int x = e.px(1); x <= e.px(40); ++x) {
    const double s = e.x.lo + (x - e.left) * (e.x.hi - e.x.lo) / (e.right - e.left);
    const int expect = e.py(0.5 + 0.01 * s);
    int lit = 0;
    for (int yy = e.top; yy <= e.bottom; ++yy)
      if (fig.image.at(x, yy) == rise) {
        ++lit;
        CHECK(std::abs(yy - expect) <= 2);
      }
    CHECK(lit >= 1);
  }
}

TEST_CASE("plot: round ticks, unmeasured cells skipped, text in the bitmap font", "[plot]") {
  const Axis a = nice_axis(0.013, 0.087, 5);
  CHECK(a.lo == Approx(0.0));
  CHECK(a.hi == Approx(0.1));
  REQUIRE(a.ticks.size() == 6);
  CHECK(a.ticks[1] == Approx(0.02));
  CHECK(tick_label(1500) == "1500");
  CHECK(tick_label(0.05) == "0.05");
  const Axis flat = nice_axis(3, 3, 5);
  CHECK(flat.lo < 3);
  CHECK(flat.hi > 3);
  // Empty cells (no measurement that step) are left out: the line joins the measured points.
  const CurveFigure fig = plot_curve(table({"step", "psnr"}, {{1, 20}, {2, NAN}, {3, NAN}, {4, 30}}), 400);
  const PlotArea& p = fig.areas[0];
  const Rgb c = fig.image.at(p.px(1), p.py(20));
  CHECK(fig.image.at(p.px(4), p.py(30)) == c);
  int lit = 0, near_line = 0;
  for (int yy = p.top; yy <= p.bottom; ++yy)
    if (fig.image.at(p.px(2.5), yy) == c) ++lit, near_line += std::abs(yy - p.py(25)) <= 1;
  CHECK(lit >= 1);
  CHECK(near_line == lit);
  // The mapping: the axis ends on the plot area's edges, larger values higher up.
  PlotArea m;
  m.left = 10, m.right = 110, m.top = 20, m.bottom = 70;
  m.x = {0, 100, {}}, m.y = {0, 50, {}};
  CHECK(m.px(0) == 10);
  CHECK(m.px(100) == 110);
  CHECK(m.px(50) == 60);
  CHECK(m.py(0) == 70);
  CHECK(m.py(50) == 20);
  CHECK(m.py(10) == 60);
  // Drawn: a series from 0 to 1 (the axis' own ends) touches the frame's inner edges, bottom left
  // and top right, and leaves the frame itself alone.
  std::vector<std::vector<double>> rows;
  for (int s = 0; s <= 10; ++s) rows.push_back({double(s), s / 10.0});
  const CurveFigure ramp = plot_curve(table({"step", "loss"}, rows), 300);
  const PlotArea& q = ramp.areas[0];
  REQUIRE(q.y.lo == 0.0);
  REQUIRE(q.y.hi == 1.0);
  const Rgb ink = ramp.image.at(q.left, q.bottom);
  const Rgb frame = ramp.image.at(q.left - 1, (q.top + q.bottom) / 2);
  CHECK(!(ink == frame));
  CHECK(ramp.image.at(q.left, q.bottom + 1) == frame);
  CHECK(ramp.image.at(q.right, q.top) == ink);
  CHECK(ramp.image.at(q.right, q.top - 1) == frame);
  Raster r(20, 12, {0, 0, 0});
  r.text(2, 1, "7", {255, 255, 255});
  for (int gy = 0; gy < kGlyphH; ++gy)
    for (int gx = 0; gx < kGlyphW; ++gx) CHECK((r.at(2 + gx, 2 + gy) == Rgb{255, 255, 255}) == glyph_lit('7', gx, gy));
}

TEST_CASE("plot: a malformed curve.csv is refused naming the file, the line and the cell", "[plot]") {
  const fs::path dir = evflow::test::fresh_dir("evflow_plot_bad");
  std::ofstream(dir / "a.csv") << "step,loss\n1,0.5\n2,abc\n";
  std::ofstream(dir / "b.csv") << "step,loss\n1,0.5,7\n";
  CHECK_THROWS_WITH(read_curve_csv(dir / "a.csv"), Catch::Contains("a.csv:3") && Catch::Contains("'abc'"));
  CHECK_THROWS_WITH(read_curve_csv(dir / "b.csv"), Catch::Contains("b.csv:2") && Catch::Contains("3 cells"));
  CHECK_THROWS_WITH(read_curve_csv(dir / "none.csv"), Catch::Contains("none.csv"));
}

TEST_CASE(
    "plot: training writes curve.csv with the PSNR every log_every steps and curve.png, which evflow plot redraws",
    "[plot][gpu]") {
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_plot_run");
  std::string out;
  REQUIRE(test::run_evflow(dir, "simulate --scene gallery --out data --width 32 --height 24 --blur-px 3 --seed 4",
                           out) == 0);
  const int rc = test::run_evflow(
      dir, "train data --out run method=plain iterations=6 log_every=3 init_gaussians=300 max_gaussians=600", out);
  INFO(out);
  REQUIRE(rc == 0);
  const CurveTable t = read_curve_csv(dir / "run" / "curve.csv");
  REQUIRE(t.rows.size() == 6);
  const int psnr = t.column("psnr");
  REQUIRE(psnr >= 0);
  for (const auto& row : t.rows) {
    const bool measured = int(row[0]) % 3 == 0;
    CHECK(std::isfinite(row[size_t(psnr)]) == measured);
    if (measured) CHECK((row[size_t(psnr)] > 5 && row[size_t(psnr)] < 60));
  }
  const io::Image png = io::read_image(dir / "run" / "curve.png");
  CHECK(png.height == uint32_t(plot_curve(t).image.height()));
  REQUIRE(test::run_evflow(dir, "plot run --out again.png", out) == 0);
  CHECK(test::slurp(dir / "again.png") == test::slurp(dir / "run" / "curve.png"));
  std::ofstream(dir / "run" / "curve.csv", std::ios::app) << "7,0,x,1,0,1,\n";
  CHECK(test::run_evflow(dir, "plot run", out) != 0);
  CHECK(out.find("curve.csv:8") != std::string::npos);
  fs::remove_all(dir);
}
