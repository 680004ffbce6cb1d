#include "pose_estimation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "events/edi.h"
#include "io/colmap_model.h"
#include "io/image.h"
#include "train/training_data.h"

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

// COLMAP's image name of each view: training views first (t000_<name>.png), then novel views,
// so that names sort in recording order for the sequential matcher.
std::string frame_name(bool novel, size_t i, const std::string& view) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%c%03zu_", novel ? 'n' : 't', i);
  return buf + view + ".png";
}

io::Image training_frame(const io::Dataset& data, size_t i, bool edi) {
  const io::View& v = data.train[i];
  if (!edi) return v.blurry;
  if (data.events.size() == 0)
    throw std::invalid_argument("the dataset in '" + data.root + "' has no event stream for EDI frames: use --blurry");
  auto [pos, neg] = event_thresholds(data, TrainConfig{});
  io::Image out = v.blurry;
  out.data = events::edi_deblur(v.blurry.data.data(), v.blurry.channels, data.events, v.exposure_start, v.exposure_end,
                                events::EdiThresholds{pos, neg, {}, {}});
  for (float& x : out.data) x = std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 0.0f;
  return out;
}

void write_frames(const io::Dataset& data, const fs::path& dir, bool edi) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (size_t i = 0; i < data.train.size(); ++i)
    io::write_image(dir / frame_name(false, i, data.train[i].name), training_frame(data, i, edi));
  for (size_t i = 0; i < data.novel.size(); ++i) {
    const io::View& v = data.novel[i];
    if (!v.sharp_mid) throw std::invalid_argument("novel view '" + v.name + "' has no image to register");
    io::write_image(dir / frame_name(true, i, v.name), *v.sharp_mid);
  }
}

// The points worth keeping: seen by at least 3 images (two-view points are often far off, at
// small triangulation angles) with a mean reprojection error under 2 px.
bool reliable(const io::ColmapPoint& p) { return p.image_ids.size() >= 3 && p.error < 2.0; }

// Near and far from the depths of the reliable sparse points in the views that see them: the 1st
// and 99th percentiles over all (view, point) pairs, widened by 20 %.
std::pair<double, double> depth_bounds(const io::ColmapModel& m) {
  std::map<uint32_t, const Camera*> cams;
  for (const auto& im : m.images) cams[im.id] = &im.camera;
  std::vector<double> z;
  for (const auto& p : m.points)
    for (uint32_t id : reliable(p) ? p.image_ids : std::vector<uint32_t>{}) {
      auto c = cams.find(id);
      if (c == cams.end()) continue;
      const auto& R = c->second->R;
      const double d = R[6] * p.xyz[0] + R[7] * p.xyz[1] + R[8] * p.xyz[2] + c->second->t[2];
      if (d > 0) z.push_back(d);
    }
  if (z.empty()) throw std::runtime_error("COLMAP's model has no point seen by 3 views in front of its cameras");
  std::sort(z.begin(), z.end());
  const double lo = z[size_t(0.01 * double(z.size() - 1))], hi = z[size_t(0.99 * double(z.size() - 1))];
  return {0.8 * lo, 1.2 * hi};
}

// The reliable points as x y z r g b rows (colours display sRGB in [0, 1]); `mean_error` over
// every point of the model.
std::vector<float> sparse_points(const io::ColmapModel& m, double& mean_error) {
  std::vector<float> pts;
  mean_error = 0;
  for (const auto& p : m.points) {
    mean_error += p.error / double(m.points.size());
    if (!reliable(p)) continue;
    for (int k = 0; k < 3; ++k) pts.push_back(float(p.xyz[k]));
    for (int k = 0; k < 3; ++k) pts.push_back(float(p.rgb[k]) / 255.0f);
  }
  return pts;
}

std::vector<std::string> train_names(const io::Dataset& d) {
  std::vector<std::string> names;
  for (const io::View& v : d.train) names.push_back(v.name);
  return names;
}

}  // namespace

PoseEstimate estimate_poses(const io::Dataset& input, const fs::path& work, const PoseOptions& opt) {
  if (input.train.empty()) throw std::invalid_argument("the dataset in '" + input.root + "' has no training views");
  std::printf("writing %zu %s frames and %zu novel views to %s\n", input.train.size(), opt.edi ? "EDI" : "blurry",
              input.novel.size(), (work / "images").c_str());
  write_frames(input, work / "images", opt.edi);
  const fs::path model_dir = run_colmap(work, input.train[0].camera, opt.colmap);
  const io::ColmapModel model = model_dir.empty() ? io::ColmapModel{} : io::read_colmap_text(model_dir);
  std::map<std::string, const io::ColmapImage*> by_name;
  for (const auto& im : model.images) by_name[im.name] = &im;

  PoseEstimate e;
  e.dataset = input;
  e.views = input.train.size() + input.novel.size();
  std::vector<Camera> estimated, reference;
  auto place = [&](io::View& v, const std::string& name) {
    auto it = by_name.find(name);
    if (it == by_name.end()) {
      e.missing.push_back(v.name);
      return;
    }
    e.registered_views.push_back(v.name);
    reference.push_back(v.camera);
    v.camera.R = it->second->camera.R;
    v.camera.t = it->second->camera.t;
    estimated.push_back(v.camera);
  };
  for (size_t i = 0; i < e.dataset.train.size(); ++i)
    place(e.dataset.train[i], frame_name(false, i, input.train[i].name));
  for (size_t i = 0; i < e.dataset.novel.size(); ++i)
    place(e.dataset.novel[i], frame_name(true, i, input.novel[i].name));
  if (input.layout != "recording" && estimated.size() >= 3)
    e.errors = pose_errors(estimated, reference, camera_extent(reference));
  e.dataset.points = sparse_points(model, e.reprojection_px);
  if (!e.missing.empty()) return e;  // no dataset will be written: the bounds are not needed
  std::tie(e.dataset.near, e.dataset.far) = depth_bounds(model);
  return e;
}

nlohmann::json pose_report(const PoseEstimate& e, const PoseOptions& opt) {
  nlohmann::json r = {{"frames", opt.edi ? "edi" : "blurry"},
                      {"matcher", opt.colmap.matcher},
                      {"views", e.views},
                      {"registered", e.views - e.missing.size()},
                      {"not_registered", e.missing},
                      {"train_views", train_names(e.dataset)},
                      {"points", e.dataset.points.size() / 6},
                      {"reprojection_px", e.reprojection_px},
                      {"near", e.dataset.near},
                      {"far", e.dataset.far}};
  if (e.errors)
    r["vs_input_poses"] = {{"rot_mean_deg", e.errors->rot_mean_deg},
                           {"rot_max_deg", e.errors->rot_max_deg},
                           {"trans_mean_pct", e.errors->trans_mean_pct},
                           {"trans_max_pct", e.errors->trans_max_pct},
                           {"relative_rot_mean_deg", e.errors->relative_rot_mean_deg},
                           {"views", e.registered_views},
                           {"rot_deg", e.errors->rot_deg},
                           {"trans_pct", e.errors->trans_pct},
                           {"scale", e.errors->alignment.scale}};
  return r;
}

}  // namespace evflow::app
