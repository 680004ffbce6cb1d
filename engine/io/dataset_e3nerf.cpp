// Reader of E3NeRF Real-World-Challenge folders (events/ + gt/); docs/datasets.md.
#include "io/dataset_formats.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "io/events_txt.h"
#include "io/llff.h"

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The time unit of an event file, from its first event's timestamp: seconds when it has a decimal
// point or an exponent, else microseconds. Empty when the file has no event line.
std::optional<TimeUnit> detect_time_unit(const fs::path& epath) {
  std::ifstream f(epath);
  std::string line;
  while (std::getline(f, line)) {
    size_t s = line.find_first_not_of(" \t\r");
    if (s == std::string::npos || line[s] == '#') continue;
    size_t e = line.find_first_of(" \t,", s);
    if (e == std::string::npos) continue;  // a lone token: let the reader complain
    const std::string tok = line.substr(s, e - s);
    return tok.find_first_of(".eE") != std::string::npos ? TimeUnit::s : TimeUnit::us;
  }
  return std::nullopt;
}

// The per-view streams merged by time (stable: ties keep view order).
void merge_by_time(const std::vector<EventStream>& per_view, EventStream& all) {
  size_t total = 0;
  for (auto& e : per_view) total += e.size();
  all.reserve(total);
  bool sorted = true;
  for (size_t k = 1; k < per_view.size(); ++k)
    if (per_view[k].t.front() < per_view[k - 1].t.back()) sorted = false;
  if (sorted) {
    for (auto& e : per_view)
      for (size_t i = 0; i < e.size(); ++i) all.push(e.x[i], e.y[i], e.t[i], e.p[i]);
    return;
  }
  std::vector<std::pair<size_t, size_t>> idx;  // (view, event)
  idx.reserve(total);
  for (size_t k = 0; k < per_view.size(); ++k)
    for (size_t i = 0; i < per_view[k].size(); ++i) idx.emplace_back(k, i);
  std::stable_sort(idx.begin(), idx.end(),
                   [&](auto a, auto b) { return per_view[a.first].t[a.second] < per_view[b.first].t[b.second]; });
  for (auto [k, i] : idx) all.push(per_view[k].x[i], per_view[k].y[i], per_view[k].t[i], per_view[k].p[i]);
}

// Training view i: its blurry image (which fixes W x H when it is the first) and its events,
// whose first and last timestamps are the exposure.
View read_train_view(const fs::path& dir, const fs::path& img, size_t i, const PosesBounds& pb, const fs::path& ppath,
                     uint32_t& W, uint32_t& H, std::optional<TimeUnit>& unit, std::vector<EventStream>& per_view) {
  View v;
  v.name = img.stem().string();
  v.blurry = load_view_image(img, W, H);
  if (!W) {
    W = v.blurry.width;
    H = v.blurry.height;
  }
  v.camera = pb.cameras[i];
  fit_camera_to_image(v.camera, W, H, ppath, i, img);
  const fs::path epath = dir / "events" / (v.name + ".txt");
  require_file(epath, "event file of view " + v.name);
  if (!unit) unit = detect_time_unit(epath);
  TxtReadOptions o;
  o.unit = unit.value_or(TimeUnit::s);
  o.polarity = PolarityCoding::one_else_negative;
  o.width = W;
  o.height = H;
  EventStream ev = read_events_txt(epath, o);
  if (ev.size() == 0) fail(epath, "has no events (the exposure window is first..last event)");
  v.exposure_start = ev.t.front();
  v.exposure_end = ev.t.back();
  per_view.push_back(std::move(ev));
  return v;
}

}  // namespace

Dataset load_e3nerf(const fs::path& dir, const LoadOptions& opt) {
  Dataset ds;
  ds.layout = "e3nerf";
  ds.root = dir.string();
  const auto imgs = list_files(dir / "images", is_image_file);
  const auto gts = list_files(dir / "gt", is_image_file);
  if (imgs.empty()) fail(dir / "images", "no training images");
  const fs::path ppath = dir / "poses_bounds.npy";
  require_file(ppath, "poses file");
  PosesBounds pb = read_poses_bounds(ppath);
  if (pb.rows.size() != imgs.size() + gts.size())
    fail(ppath, "has " + std::to_string(pb.rows.size()) + " poses but there are " + std::to_string(imgs.size()) +
                    " images in images/ and " + std::to_string(gts.size()) +
                    " in gt/ (expected training rows then test rows)");
  uint32_t W = 0, H = 0;
  std::optional<TimeUnit> unit = opt.e3nerf_time_unit;
  std::vector<EventStream> per_view;
  for (size_t i = 0; i < imgs.size(); ++i)
    ds.train.push_back(read_train_view(dir, imgs[i], i, pb, ppath, W, H, unit, per_view));
  for (size_t i = 0; i < gts.size(); ++i) {
    View v;
    v.name = gts[i].stem().string();
    v.sharp_mid = load_view_image(gts[i], W, H);
    v.camera = pb.cameras[imgs.size() + i];
    fit_camera_to_image(v.camera, W, H, ppath, imgs.size() + i, gts[i]);
    ds.novel.push_back(std::move(v));
  }
  ds.events.width = W;
  ds.events.height = H;
  merge_by_time(per_view, ds.events);
  set_bounds(ds, pb);
  ds.manifest = {{"layout", "e3nerf"},
                 {"resolution", {W, H}},
                 {"event_time_unit", to_string(unit.value_or(TimeUnit::s))},
                 {"exposure", "first..last event of events/<view>.txt"},
                 {"train_views", ds.train.size()},
                 {"novel_views", ds.novel.size()}};
  return ds;
}

}  // namespace evflow::io::detail
