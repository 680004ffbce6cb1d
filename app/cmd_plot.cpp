// evflow plot RUN|curve.csv [--out FILE.png]: the loss curves of a training run as a PNG.
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "plot/curve_plot.h"

namespace evflow::app {

namespace fs = std::filesystem;

static int run_plot(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf(
        "usage: evflow plot RUN|curve.csv [--out FILE.png]\n"
        "  Draws a run's curve.csv against the step, one chart per quantity: the weighted total loss,\n"
        "  each loss term (unweighted), the training PSNR; written to RUN/curve.png unless --out says\n"
        "  otherwise (training writes it too, with every checkpoint).\n");
    return 0;
  }
  const std::string out = p.value("--out");
  p.reject_unknown();
  const auto pos = p.positional();
  if (pos.size() != 1) throw std::invalid_argument("usage: evflow plot RUN|curve.csv [--out FILE.png] (see --help)");
  const fs::path src = pos[0];
  const fs::path csv = fs::is_directory(src) ? src / "curve.csv" : src;
  const fs::path png = !out.empty() ? fs::path(out) : csv.parent_path() / "curve.png";
  plot::write_curve_png(csv, png);
  std::printf("wrote %s\n", png.c_str());
  return 0;
}

static Command reg("plot", "draw a run's loss and PSNR curves (curve.csv) as curve.png", run_plot);

}  // namespace evflow::app
