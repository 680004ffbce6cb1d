#include "io/dataset_writer.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/events_h5.h"
#include "io/llff.h"
#include "io/npy.h"

namespace evflow::io {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::invalid_argument bad(const fs::path& dir, const std::string& what) {
  return std::invalid_argument(dir.string() + ": write_evflow_dataset: " + what);
}

// Throws std::invalid_argument on what our layout cannot hold: no training views, bad or
// duplicate names, missing images, sizes that differ, event counts that do not match their shape.
void check_dataset(const Dataset& ds, const fs::path& dir, const WriteOptions& opt) {
  if (ds.train.empty()) throw bad(dir, "no training views");
  if (opt.image_ext != ".png" && opt.image_ext != ".exr") throw bad(dir, "image_ext must be .png or .exr");
  const uint32_t W = ds.train[0].blurry.width, H = ds.train[0].blurry.height;
  std::vector<std::string> names;
  auto check = [&](const View& v, const Image* im, const char* kind) {
    if (v.name.empty() || v.name.find_first_of("/\\") != std::string::npos || v.name[0] == '.')
      throw bad(dir, "bad view name '" + v.name + "'");
    if (std::find(names.begin(), names.end(), v.name) != names.end())
      throw bad(dir, "duplicate view name '" + v.name + "'");
    names.push_back(v.name);
    if (!im || im->empty()) throw bad(dir, std::string(kind) + " view '" + v.name + "' has no image");
    if (im->width != W || im->height != H)
      throw bad(dir, "view '" + v.name + "' image size differs from the first view's");
    if (v.camera.width != W || v.camera.height != H)
      throw bad(dir, "view '" + v.name + "' camera size differs from its image");
  };
  for (const View& v : ds.train) {
    check(v, &v.blurry, "training");
    if (v.sharp_mid && (v.sharp_mid->width != W || v.sharp_mid->height != H))
      throw bad(dir, "view '" + v.name + "' sharp image size");
  }
  names.clear();
  for (const View& v : ds.novel) check(v, v.sharp_mid ? &*v.sharp_mid : nullptr, "novel");
  if (!ds.event_counts.empty() &&
      (ds.event_counts_shape.size() != 3 ||
       ds.event_counts_shape[0] * ds.event_counts_shape[1] * ds.event_counts_shape[2] != ds.event_counts.size()))
    throw bad(dir, "event_counts does not match event_counts_shape");
}

}  // namespace

void write_evflow_dataset(const Dataset& ds, const fs::path& dir, const WriteOptions& opt) {
  check_dataset(ds, dir, opt);
  const uint32_t W = ds.train[0].blurry.width, H = ds.train[0].blurry.height;
  json m = ds.manifest.is_object() ? ds.manifest : json::object();
  for (const char* k : {"layout", "train_views", "novel_views", "test_rows", "exposure", "event_time_unit"}) m.erase(k);
  m["format"] = "evflow";
  m["version"] = 1;
  m["resolution"] = {W, H};
  m["time_unit"] = "s";
  m["poses"] = "poses_bounds.npy";
  m["near"] = ds.near;
  m["far"] = ds.far;
  auto intr = [](const Camera& c) { return json::array({c.fx, c.fy, c.cx, c.cy}); };
  json tr = json::array(), nv = json::array();
  std::vector<Camera> cams;
  std::vector<double> es, ee;
  for (const View& v : ds.train) {
    const std::string img = "images/" + v.name + opt.image_ext;
    write_image(dir / img, v.blurry);
    json e = {{"name", v.name},
              {"image", img},
              {"exposure", {v.exposure_start, v.exposure_end}},
              {"intrinsics", intr(v.camera)}};
    if (v.sharp_mid) {
      const std::string s = "images_gt_blur/" + v.name + opt.image_ext;
      write_image(dir / s, *v.sharp_mid);
      e["sharp"] = s;
    }
    tr.push_back(e);
    cams.push_back(v.camera);
    es.push_back(v.exposure_start);
    ee.push_back(v.exposure_end);
  }
  for (const View& v : ds.novel) {
    const std::string img = "images_gt_novel/" + v.name + opt.image_ext;
    write_image(dir / img, *v.sharp_mid);
    nv.push_back({{"name", v.name}, {"image", img}, {"intrinsics", intr(v.camera)}});
    cams.push_back(v.camera);
  }
  m["train"] = tr;
  m["novel"] = nv;
  write_poses_bounds(dir / "poses_bounds.npy", cams, std::vector<double>(cams.size(), ds.near),
                     std::vector<double>(cams.size(), ds.far));
  EventStream ev = ds.events;
  if (ev.width == 0 && ev.height == 0 && ev.size() == 0) {
    ev.width = W;
    ev.height = H;
  }
  if (ev.width != W || ev.height != H) throw bad(dir, "event sensor size differs from the image size");
  write_events_h5(dir / "events.h5", ev, es, ee);
  m["events"] = "events.h5";
  if (!ds.event_counts.empty()) {
    write_npy(dir / "event_counts.npy", ds.event_counts_shape, ds.event_counts);
    m["event_counts"] = "event_counts.npy";
  } else {
    m.erase("event_counts");
  }
  if (!ds.points.empty()) {
    if (ds.points.size() % 6) throw bad(dir, "points must be x y z r g b per point");
    write_npy(dir / "points3D.npy", {ds.points.size() / 6, 6}, ds.points);
    m["points"] = "points3D.npy";
  } else {
    m.erase("points");
  }
  const std::string text = m.dump(2) + "\n";
  write_file_atomic(dir / "dataset.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    close_or_throw(f, dir / "dataset.json");
  });
}

}  // namespace evflow::io
