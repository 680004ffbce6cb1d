// Reader of our layout (dataset.json); docs/datasets.md.
#include "io/dataset_formats.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "io/events_h5.h"
#include "io/npy.h"

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What every part of the manifest is read against.
struct Manifest {
  fs::path dir, path, poses_path;
  const json& m;
  uint32_t width = 0, height = 0;
  PosesBounds poses;
};

void read_resolution(Manifest& mf) {
  const json& res = get(mf.m, "resolution", mf.path, "manifest");
  if (!res.is_array() || res.size() != 2) fail(mf.path, "\"resolution\" must be [width, height]");
  mf.width = res[0].get<uint32_t>();
  mf.height = res[1].get<uint32_t>();
  if (!mf.width || !mf.height) fail(mf.path, "\"resolution\" must be positive");
}

// A view's name and camera: pose row `row`, the entry's own intrinsics when it has them.
View make_view(const Manifest& mf, const json& e, size_t row, const std::string& where) {
  View v;
  v.name = get(e, "name", mf.path, where).get<std::string>();
  v.camera = mf.poses.cameras[row];
  if (e.contains("intrinsics")) {
    const json& k = e["intrinsics"];
    if (!k.is_array() || k.size() != 4) fail(mf.path, where + ": \"intrinsics\" must be [fx, fy, cx, cy]");
    v.camera.fx = k[0].get<double>();
    v.camera.fy = k[1].get<double>();
    v.camera.cx = k[2].get<double>();
    v.camera.cy = k[3].get<double>();
  }
  if (v.camera.width != mf.width || v.camera.height != mf.height)
    fail(mf.poses_path, "row " + std::to_string(row) + " is for " + std::to_string(v.camera.width) + "x" +
                            std::to_string(v.camera.height) + " images, the manifest says " + std::to_string(mf.width) +
                            "x" + std::to_string(mf.height));
  return v;
}

View read_train_view(const Manifest& mf, const json& e, size_t i) {
  const std::string where = "train[" + std::to_string(i) + "]";
  View v = make_view(mf, e, i, where);
  v.blurry = load_view_image(mf.dir / get(e, "image", mf.path, where).get<std::string>(), mf.width, mf.height);
  if (e.contains("sharp")) v.sharp_mid = load_view_image(mf.dir / e["sharp"].get<std::string>(), mf.width, mf.height);
  const json& ex = get(e, "exposure", mf.path, where);
  if (!ex.is_array() || ex.size() != 2) fail(mf.path, where + ": \"exposure\" must be [start, end] in seconds");
  v.exposure_start = ex[0].get<double>();
  v.exposure_end = ex[1].get<double>();
  if (!(v.exposure_end >= v.exposure_start)) fail(mf.path, where + ": exposure ends before it starts");
  return v;
}

void read_views(const Manifest& mf, Dataset& ds) {
  const json& tr = get(mf.m, "train", mf.path, "manifest");
  const json nv = mf.m.value("novel", json::array());
  if (!tr.is_array() || !nv.is_array()) fail(mf.path, "\"train\" and \"novel\" must be arrays");
  if (mf.poses.rows.size() != tr.size() + nv.size())
    fail(mf.poses_path, "has " + std::to_string(mf.poses.rows.size()) + " poses but " + mf.path.string() + " lists " +
                            std::to_string(tr.size()) + " training + " + std::to_string(nv.size()) + " novel views");
  for (size_t i = 0; i < tr.size(); ++i) ds.train.push_back(read_train_view(mf, tr[i], i));
  for (size_t i = 0; i < nv.size(); ++i) {
    const std::string where = "novel[" + std::to_string(i) + "]";
    View v = make_view(mf, nv[i], tr.size() + i, where);
    v.sharp_mid = load_view_image(mf.dir / get(nv[i], "image", mf.path, where).get<std::string>(), mf.width, mf.height);
    ds.novel.push_back(std::move(v));
  }
}

// The event file, whose exposure windows (when it stores them) must match the manifest's.
void read_events(const Manifest& mf, Dataset& ds) {
  if (!mf.m.contains("events") || mf.m["events"].is_null()) return;
  const fs::path epath = mf.dir / mf.m["events"].get<std::string>();
  require_file(epath, "event file");
  H5ReadOptions o;
  o.width = mf.width;
  o.height = mf.height;
  H5Events he = read_events_h5(epath, o);
  ds.events = std::move(he.events);
  if (he.exposure_start.empty()) return;
  if (he.exposure_start.size() != ds.train.size())
    fail(epath, "has " + std::to_string(he.exposure_start.size()) + " exposure windows for " +
                    std::to_string(ds.train.size()) + " training views");
  for (size_t i = 0; i < ds.train.size(); ++i)
    if (std::fabs(he.exposure_start[i] - ds.train[i].exposure_start) > 1e-6 ||
        std::fabs(he.exposure_end[i] - ds.train[i].exposure_end) > 1e-6)
      fail(epath, "exposure window " + std::to_string(i) + " disagrees with " + mf.path.string());
}

// The optional arrays: binned event counts and sparse points.
void read_arrays(const Manifest& mf, Dataset& ds) {
  if (mf.m.contains("event_counts") && !mf.m["event_counts"].is_null()) {
    const fs::path cpath = mf.dir / mf.m["event_counts"].get<std::string>();
    NpyArray a = read_npy(cpath);
    if (a.shape.size() != 3 || a.shape[0] != ds.train.size() || a.shape[2] != size_t(mf.width) * mf.height)
      fail(cpath, "event counts must have shape [training views, bins, H*W]");
    ds.event_counts = a.to_float();
    ds.event_counts_shape = a.shape;
  }
  if (mf.m.contains("points") && !mf.m["points"].is_null()) {
    const fs::path ppath = mf.dir / mf.m["points"].get<std::string>();
    NpyArray a = read_npy(ppath);
    if (a.shape.size() != 2 || a.shape[1] != 6) fail(ppath, "sparse points must have shape [N, 6] (x y z r g b)");
    ds.points = a.to_float();
  }
}

}  // namespace

Dataset load_evflow(const fs::path& dir) {
  Dataset ds;
  ds.layout = "evflow";
  ds.root = dir.string();
  const fs::path mpath = dir / "dataset.json";
  ds.manifest = read_json_file(mpath);
  try {
    Manifest mf{dir, mpath, dir / ds.manifest.value("poses", std::string("poses_bounds.npy")), ds.manifest};
    read_resolution(mf);
    require_file(mf.poses_path, "poses file");
    mf.poses = read_poses_bounds(mf.poses_path);
    read_views(mf, ds);
    set_bounds(ds, mf.poses);
    if (mf.m.contains("near")) ds.near = mf.m["near"].get<double>();
    if (mf.m.contains("far")) ds.far = mf.m["far"].get<double>();
    read_events(mf, ds);
    read_arrays(mf, ds);
  } catch (const json::exception& e) { fail(mpath, std::string("malformed manifest: ") + e.what()); }
  return ds;
}

}  // namespace evflow::io::detail
