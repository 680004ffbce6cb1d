// evflow poses: camera poses by COLMAP on EDI-deblurred frames, written as a new dataset.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "io/atomic_file.h"
#include "io/dataset.h"
#include "io/dataset_writer.h"
#include "pose_estimation.h"

namespace evflow::app {

namespace fs = std::filesystem;

static const char* kPosesHelp =
    "usage: evflow poses DATA [--out DATA2] [--matcher exhaustive|sequential] [--edi|--blurry]\n"
    "Estimates every view's camera pose with COLMAP (CPU SIFT, one pinhole camera with the dataset's\n"
    "intrinsics held fixed) and writes DATA with those poses as a new dataset in our layout\n"
    "(docs/datasets.md): COLMAP's world frame, near/far from its sparse points, the points as\n"
    "points3D.npy (training key init=points). Training views go in as their EDI estimate at\n"
    "mid-exposure, novel views as their sharp images, all in one model. DATA is any dataset layout or\n"
    "a recording (recording.json). COLMAP's work and logs stay in DATA2/colmap/, its summary in\n"
    "DATA2/colmap/report.json (with the pose error against DATA's own poses when it has some).\n\n"
    "  --out DIR                  output dataset (default: DATA_colmap next to DATA)\n"
    "  --matcher exhaustive|sequential   COLMAP's feature matching (default: exhaustive)\n"
    "  --edi                      EDI frames from the events (default)\n"
    "  --blurry                   the blurry frames as they are\n"
    "  --threads N                COLMAP's threads (default: every core)\n"
    "  --json                     print the report as JSON on the last line\n"
    "The COLMAP binary is `colmap` on the PATH, or EVF_COLMAP.\n";

namespace {

// DATA2 may be new, empty, or an earlier output (dataset.json or colmap/ inside); nothing else
// is written into.
void check_output(const fs::path& out, const fs::path& in) {
  std::error_code ec;
  if (fs::equivalent(out, in, ec)) throw std::invalid_argument("--out must differ from DATA");
  if (!fs::exists(out)) return;
  if (!fs::is_directory(out)) throw std::invalid_argument(out.string() + ": exists and is not a folder");
  if (!fs::is_empty(out) && !fs::exists(out / "dataset.json") && !fs::exists(out / "colmap"))
    throw std::invalid_argument(out.string() +
                                ": not empty and not an earlier `evflow poses` output; choose another --out");
}

void print_summary(const PoseEstimate& e) {
  std::printf("registered %zu of %zu views, %zu sparse points (mean reprojection error %.2f px)",
              e.views - e.missing.size(), e.views, e.dataset.points.size() / 6, e.reprojection_px);
  if (e.missing.empty()) std::printf(", near %.3g far %.3g", e.dataset.near, e.dataset.far);
  std::printf("\n");
  if (e.errors)
    std::printf(
        "vs the input's poses after a similarity alignment: rotation mean %.3f max %.3f deg, translation mean "
        "%.3f max %.3f %% of the camera extent; relative rotations %.3f deg (mean over pairs)\n",
        e.errors->rot_mean_deg, e.errors->rot_max_deg, e.errors->trans_mean_pct, e.errors->trans_max_pct,
        e.errors->relative_rot_mean_deg);
}

}  // namespace

static int run_poses(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf("%s", kPosesHelp);
    return 0;
  }
  PoseOptions opt;
  const bool blurry = p.flag("--blurry"), edi = p.flag("--edi");
  if (blurry && edi) throw std::invalid_argument("--edi and --blurry exclude each other");
  opt.edi = !blurry;
  opt.colmap.matcher = p.value("--matcher", "exhaustive");
  opt.colmap.threads = int(p.integer("--threads", 0, 0, 4096));
  if (const char* bin = std::getenv("EVF_COLMAP")) opt.colmap.binary = bin;
  const bool json = p.flag("--json");
  std::string out = p.value("--out");
  p.reject_unknown();
  const auto pos = p.positional();
  if (pos.size() != 1) throw std::invalid_argument("expected one dataset folder (evflow poses --help)");
  const fs::path in = fs::absolute(pos[0]).lexically_normal();
  if (out.empty()) out = (in.has_filename() ? in : in.parent_path()).string() + "_colmap";
  if (opt.colmap.matcher != "exhaustive" && opt.colmap.matcher != "sequential")
    throw std::invalid_argument("--matcher must be exhaustive or sequential, got '" + opt.colmap.matcher + "'");
  check_output(out, in);
  require_colmap(opt.colmap);

  const auto t0 = std::chrono::steady_clock::now();
  const io::Dataset data = io::load_dataset(in);
  const fs::path work = fs::path(out) / "colmap";
  PoseEstimate e = estimate_poses(data, work, opt);
  nlohmann::json report = pose_report(e, opt);
  report["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  io::write_file_atomic(work / "report.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << report.dump(2) << "\n";
    io::close_or_throw(f, work / "report.json");
  });
  print_summary(e);
  if (json) std::printf("%s\n", report.dump().c_str());
  if (!e.missing.empty())
    throw std::runtime_error("COLMAP registered " + std::to_string(e.views - e.missing.size()) + " of " +
                             std::to_string(e.views) + " views; not registered: " + join(e.missing, ", ") +
                             " (frames in " + (work / "images").string() + ", logs in " + work.string() + ")");
  e.dataset.manifest["poses_from"] = {{"colmap", report}};
  io::write_evflow_dataset(e.dataset, out);
  std::printf("wrote %s (%.1f s)\n", out.c_str(), report["seconds"].get<double>());
  return 0;
}

static Command reg("poses", "camera poses by COLMAP on EDI-deblurred frames, as a new dataset", run_poses);

}  // namespace evflow::app
