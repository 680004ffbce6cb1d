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

Dataset load_evflow(const fs::path& dir) {
  const fs::path mpath = dir / "dataset.json";
  Dataset ds;
  ds.layout = "evflow";
  ds.root = dir.string();
  ds.manifest = read_json_file(mpath);
  const json& m = ds.manifest;
  try {
    const json& res = get(m, "resolution", mpath, "manifest");
    if (!res.is_array() || res.size() != 2) fail(mpath, "\"resolution\" must be [width, height]");
    const uint32_t W = res[0].get<uint32_t>(), H = res[1].get<uint32_t>();
    if (!W || !H) fail(mpath, "\"resolution\" must be positive");
    const fs::path ppath = dir / m.value("poses", std::string("poses_bounds.npy"));
    require_file(ppath, "poses file");
    PosesBounds pb = read_poses_bounds(ppath);
    const json& tr = get(m, "train", mpath, "manifest");
    const json nv = m.value("novel", json::array());
    if (!tr.is_array() || !nv.is_array()) fail(mpath, "\"train\" and \"novel\" must be arrays");
    if (pb.rows.size() != tr.size() + nv.size())
      fail(ppath, "has " + std::to_string(pb.rows.size()) + " poses but " + mpath.string() + " lists " +
                      std::to_string(tr.size()) + " training + " + std::to_string(nv.size()) + " novel views");
    auto make_view = [&](const json& e, size_t row, const std::string& where) {
      View v;
      v.name = get(e, "name", mpath, where).get<std::string>();
      v.camera = pb.cameras[row];
      if (e.contains("intrinsics")) {
        const json& k = e["intrinsics"];
        if (!k.is_array() || k.size() != 4) fail(mpath, where + ": \"intrinsics\" must be [fx, fy, cx, cy]");
        v.camera.fx = k[0].get<double>();
        v.camera.fy = k[1].get<double>();
        v.camera.cx = k[2].get<double>();
        v.camera.cy = k[3].get<double>();
      }
      if (v.camera.width != W || v.camera.height != H)
        fail(ppath, "row " + std::to_string(row) + " is for " + std::to_string(v.camera.width) + "x" +
                        std::to_string(v.camera.height) + " images, the manifest says " + std::to_string(W) + "x" +
                        std::to_string(H));
      return v;
    };
    for (size_t i = 0; i < tr.size(); ++i) {
      const std::string where = "train[" + std::to_string(i) + "]";
      View v = make_view(tr[i], i, where);
      v.blurry = load_view_image(dir / get(tr[i], "image", mpath, where).get<std::string>(), W, H);
      if (tr[i].contains("sharp")) v.sharp_mid = load_view_image(dir / tr[i]["sharp"].get<std::string>(), W, H);
      const json& ex = get(tr[i], "exposure", mpath, where);
      if (!ex.is_array() || ex.size() != 2) fail(mpath, where + ": \"exposure\" must be [start, end] in seconds");
      v.exposure_start = ex[0].get<double>();
      v.exposure_end = ex[1].get<double>();
      if (!(v.exposure_end >= v.exposure_start)) fail(mpath, where + ": exposure ends before it starts");
      ds.train.push_back(std::move(v));
    }
    for (size_t i = 0; i < nv.size(); ++i) {
      const std::string where = "novel[" + std::to_string(i) + "]";
      View v = make_view(nv[i], tr.size() + i, where);
      v.sharp_mid = load_view_image(dir / get(nv[i], "image", mpath, where).get<std::string>(), W, H);
      ds.novel.push_back(std::move(v));
    }
    set_bounds(ds, pb);
    if (m.contains("near")) ds.near = m["near"].get<double>();
    if (m.contains("far")) ds.far = m["far"].get<double>();
    if (m.contains("events") && !m["events"].is_null()) {
      const fs::path epath = dir / m["events"].get<std::string>();
      require_file(epath, "event file");
      H5ReadOptions o;
      o.width = W;
      o.height = H;
      H5Events he = read_events_h5(epath, o);
      ds.events = std::move(he.events);
      if (!he.exposure_start.empty()) {
        if (he.exposure_start.size() != ds.train.size())
          fail(epath, "has " + std::to_string(he.exposure_start.size()) + " exposure windows for " +
                          std::to_string(ds.train.size()) + " training views");
        for (size_t i = 0; i < ds.train.size(); ++i)
          if (std::fabs(he.exposure_start[i] - ds.train[i].exposure_start) > 1e-6 ||
              std::fabs(he.exposure_end[i] - ds.train[i].exposure_end) > 1e-6)
            fail(epath, "exposure window " + std::to_string(i) + " disagrees with " + mpath.string());
      }
    }
    if (m.contains("event_counts") && !m["event_counts"].is_null()) {
      const fs::path cpath = dir / m["event_counts"].get<std::string>();
      NpyArray a = read_npy(cpath);
      if (a.shape.size() != 3 || a.shape[0] != ds.train.size() || a.shape[2] != size_t(W) * H)
        fail(cpath, "event counts must have shape [training views, bins, H*W]");
      ds.event_counts = a.to_float();
      ds.event_counts_shape = a.shape;
    }
    if (m.contains("points") && !m["points"].is_null()) {
      const fs::path ppath = dir / m["points"].get<std::string>();
      NpyArray a = read_npy(ppath);
      if (a.shape.size() != 2 || a.shape[1] != 6) fail(ppath, "sparse points must have shape [N, 6] (x y z r g b)");
      ds.points = a.to_float();
    }
  } catch (const json::exception& e) { fail(mpath, std::string("malformed manifest: ") + e.what()); }
  return ds;
}

}  // namespace evflow::io::detail
