// evflow render SPLATS --out DIR: renders splats (a run, a .ply or a .glb) from chosen cameras
// into 8-bit sRGB PNGs: a camera file, an orbit around the splats, the dataset's views, or the
// poses along each training view's learned exposure.
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "cli.h"
#include "io/camera_json.h"
#include "metrics/srgb_metrics.h"
#include "run_files.h"
#include "splat/rasterizer.h"
#include "train/train_config.h"
#include "viewer/view_camera.h"

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

struct Shot {
  std::string name;
  Camera camera;
};

std::string numbered(const std::string& prefix, size_t i) {
  std::ostringstream s;
  s << prefix << std::setw(3) << std::setfill('0') << i;
  return s.str();
}

// Around the splats' centre, turning about "up": with a dataset, from its first training view
// (as `evflow train --view` starts) and about the up its cameras share; without one, as `evflow
// view` first looks at the splats, about the world's -y (OpenCV's up).
std::vector<Shot> orbit_shots(const GaussianCloud& cloud, const io::Dataset* data, uint32_t w, uint32_t h,
                              uint32_t frames) {
  viewer::Orbit o = viewer::initial_orbit(cloud);
  if (data && !data->train.empty()) {
    std::vector<Camera> cams;
    for (const auto& v : data->train) cams.push_back(v.camera);
    const Camera& cam = cams[0];
    const auto c = cam.center();
    double depth = 0;
    for (int k = 0; k < 3; ++k) depth += (o.target[k] - c[k]) * cam.R[6 + k];
    o = viewer::orbit_from_camera(cam, depth > 0 ? depth : o.distance, viewer::basis_from_cameras(cams));
  }
  std::vector<Shot> out;
  for (uint32_t i = 0; i < frames; ++i) {
    viewer::Orbit at = o;
    at.yaw = o.yaw + 2.0 * M_PI * i / frames;
    out.push_back({numbered("orbit_", i), viewer::orbit_camera(at, w, h)});
  }
  return out;
}

// Training views at their learned mid-exposure camera (runs) or as recorded, then novel views.
std::vector<Shot> view_shots(const io::Dataset& data, const RunFolder* run) {
  std::vector<Shot> out;
  for (size_t i = 0; i < data.train.size(); ++i)
    out.push_back(
        {"train_" + data.train[i].name, run ? run->learned_camera(data.train[i], i, 0.5) : data.train[i].camera});
  for (auto& v : data.novel) out.push_back({"novel_" + v.name, v.camera});
  return out;
}

// The 2N+1 virtual poses of each training view's learned exposure trajectory.
std::vector<Shot> exposure_shots(const io::Dataset& data, const RunFolder& run, const TrainConfig& cfg) {
  if (cfg.mode != TrainMode::Blur)
    throw std::invalid_argument("--path exposure: the run in '" + run.dir.string() +
                                "' is mode=" + mode_name(cfg.mode) + ", it learned no exposure trajectories");
  const std::vector<double> us = ExposureTrajectory::virtual_times(int(cfg.virtual_frames));
  std::vector<Shot> out;
  for (size_t i = 0; i < data.train.size(); ++i)
    for (size_t f = 0; f < us.size(); ++f)
      out.push_back({data.train[i].name + numbered("_f", f), run.learned_camera(data.train[i], i, us[f])});
  return out;
}

void print_help() {
  std::printf(
      "usage: evflow render SPLATS --out DIR [--camera cams.json | --path orbit|views|exposure]\n"
      "         [--data DIR] [--width 800] [--height 600] [--frames 36] [--background r,g,b] [--sh-degree N]\n"
      "         [--device N|name]\n"
      "  SPLATS: a training run folder, a .ply or a .glb. Writes DIR/<name>.png, 8-bit sRGB, per camera:\n"
      "  --camera F   the cameras of a JSON file (docs/cli.md: intrinsics, size, world-to-camera in OpenCV\n"
      "               axes): camera_000.png, ...\n"
      "  --path orbit (default) --frames views around the splats' centre at --width x --height: orbit_000.png,\n"
      "               ...; with a dataset (a run's or --data's) from its first training view, turning about\n"
      "               its cameras' up, else about -y\n"
      "  --path views the dataset's training views (a run: at their learned mid-exposure pose) and novel\n"
      "               views: train_<view>.png, novel_<view>.png; the dataset is the run's or --data's\n"
      "  --path exposure  a blur-mode run: each training view's 2N+1 poses along its learned exposure:\n"
      "               <view>_f000.png ... (the middle one is mid-exposure: the image `evflow eval` scores)\n"
      "  Background and antialiasing are the run's (black and off for a file) unless --background is given;\n"
      "  --sh-degree limits the SH degree used.\n");
}

std::array<float, 3> parse_background(const std::string& v) {
  float r, g, b;
  if (std::sscanf(v.c_str(), "%f,%f,%f", &r, &g, &b) != 3)
    throw std::invalid_argument("--background expects r,g,b, got '" + v + "'");
  return {r, g, b};
}

}  // namespace

static int run_render(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    print_help();
    return 0;
  }
  const std::string out_dir = p.value("--out"), camera_file = p.value("--camera"), data_dir = p.value("--data");
  const std::string path = p.value("--path", camera_file.empty() ? "orbit" : "");
  const auto [w, h] = p.image_size({800, 600});
  const uint32_t frames = uint32_t(p.integer("--frames", 36, 1, 100000));
  const std::string background = p.value("--background");
  const int sh_degree = int(p.integer("--sh-degree", -1, -1, 3));  // -1: the splats' own
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  const auto pos = p.positional();
  if (pos.size() != 1 || out_dir.empty()) throw std::invalid_argument("usage: evflow render SPLATS --out DIR (--help)");
  if (!camera_file.empty() && !path.empty()) throw std::invalid_argument("--camera and --path exclude each other");

  const fs::path src = pos[0];
  const bool is_run = fs::is_directory(src);
  std::unique_ptr<RunFolder> run = is_run ? std::make_unique<RunFolder>(RunFolder::open(src)) : nullptr;
  const GaussianCloud cloud = run ? run->checkpoint.cloud : load_splats(src);
  TrainConfig cfg;
  if (run)
    cfg.apply_json([&] {
      auto c = run->config;
      c.erase("data");
      return c;
    }());
  auto dataset = [&] {
    const std::string d = !data_dir.empty() ? data_dir : run ? run->data_dir() : "";
    if (d.empty()) throw std::invalid_argument("--path " + path + " needs a dataset: give --data DIR");
    return io::load_dataset(d);
  };

  std::vector<Shot> shots;
  if (!camera_file.empty()) {
    const auto cams = io::read_cameras_json(camera_file);
    for (size_t i = 0; i < cams.size(); ++i) shots.push_back({numbered("camera_", i), cams[i]});
  } else if (path == "orbit") {
    const std::string d = !data_dir.empty() ? data_dir : run ? run->data_dir() : "";
    const std::unique_ptr<io::Dataset> data = d.empty() ? nullptr : std::make_unique<io::Dataset>(io::load_dataset(d));
    shots = orbit_shots(cloud, data.get(), w, h, frames);
  } else if (path == "views") {
    shots = view_shots(dataset(), run.get());
  } else if (path == "exposure") {
    if (!run) throw std::invalid_argument("--path exposure needs a training run folder, not '" + src.string() + "'");
    shots = exposure_shots(dataset(), *run, cfg);
  } else {
    throw std::invalid_argument("--path must be orbit, views or exposure, not '" + path + "'");
  }

  RenderSettings s;
  s.background =
      background.empty() ? (run ? cfg.background : std::array<float, 3>{0, 0, 0}) : parse_background(background);
  s.antialiased = run && cfg.antialiased;
  s.sh_degree = sh_degree;
  gpu::Context ctx(o);
  GaussianBuffers params(ctx, cloud.size(), cloud.sh_degree, "p_");
  params.upload(cloud);
  Rasterizer r(ctx);
  RenderState state(ctx);
  fs::create_directories(out_dir);
  for (const Shot& shot : shots) {
    r.forward(params, shot.camera, s, state);
    const size_t n = size_t(shot.camera.width) * shot.camera.height * 3;
    metrics::write_png(
        fs::path(out_dir) / (shot.name + ".png"),
        metrics::quantise_srgb(state.outputs().rgb.read<float>(n), shot.camera.width, shot.camera.height, 3));
  }
  std::printf("rendered %zu image%s of %zu Gaussians into %s\n", shots.size(), shots.size() == 1 ? "" : "s",
              cloud.size(), out_dir.c_str());
  return 0;
}

static Command reg("render", "render splats (run, .ply, .glb) from a camera file, an orbit, the views or the exposures",
                   run_render);

}  // namespace evflow::app
