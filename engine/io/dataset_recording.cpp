// Reader of a recording (recording.json): frames with their exposures, events and intrinsics,
// and no poses yet; `evflow poses` turns it into a dataset. docs/datasets.md.
#include "io/dataset_formats.h"

#include "io/events_h5.h"
#include "io/events_txt.h"

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Camera intrinsics_camera(const json& k, uint32_t W, uint32_t H, const fs::path& mpath) {
  if (!k.is_array() || k.size() != 4) fail(mpath, "\"intrinsics\" must be [fx, fy, cx, cy] in pixels");
  Camera c;
  c.width = W;
  c.height = H;
  c.fx = k[0].get<double>();
  c.fy = k[1].get<double>();
  c.cx = k[2].get<double>();
  c.cy = k[3].get<double>();
  if (!(c.fx > 0 && c.fy > 0)) fail(mpath, "\"intrinsics\": the focal lengths must be positive");
  return c;
}

EventStream recording_events(const fs::path& dir, const json& m, uint32_t W, uint32_t H, const fs::path& mpath) {
  const fs::path epath = dir / get(m, "events", mpath, "manifest").get<std::string>();
  require_file(epath, "event file");
  const TimeUnit unit =
      parse_time_unit(m.value("event_time_unit", std::string(epath.extension() == ".txt" ? "s" : "us")));
  if (epath.extension() == ".txt") {
    TxtReadOptions o;
    o.unit = unit;
    o.width = W;
    o.height = H;
    return read_events_txt(epath, o);
  }
  H5ReadOptions o;
  o.unit = unit;
  o.width = W;
  o.height = H;
  return read_events_h5(epath, o).events;
}

}  // namespace

Dataset load_recording(const fs::path& dir) {
  const fs::path mpath = dir / "recording.json";
  Dataset ds;
  ds.layout = "recording";
  ds.root = dir.string();
  const json m = read_json_file(mpath);
  try {
    const json& frames = get(m, "frames", mpath, "manifest");
    if (!frames.is_array() || frames.empty()) fail(mpath, "\"frames\" must be a non-empty array");
    const json tests = m.value("test", json::array());
    uint32_t W = 0, H = 0;
    auto view = [&](const json& e, const std::string& where) {
      View v;
      const fs::path image = get(e, "image", mpath, where).get<std::string>();
      v.name = image.stem().string();
      Image im = load_view_image(dir / image, W, H);
      W = im.width, H = im.height;
      v.camera = intrinsics_camera(get(m, "intrinsics", mpath, "manifest"), W, H, mpath);
      v.sharp_mid = std::move(im);
      return v;
    };
    for (size_t i = 0; i < frames.size(); ++i) {
      const std::string where = "frames[" + std::to_string(i) + "]";
      View v = view(frames[i], where);
      v.blurry = std::move(*v.sharp_mid);
      v.sharp_mid.reset();
      const json& ex = get(frames[i], "exposure", mpath, where);
      if (!ex.is_array() || ex.size() != 2) fail(mpath, where + ": \"exposure\" must be [start, end] in seconds");
      v.exposure_start = ex[0].get<double>();
      v.exposure_end = ex[1].get<double>();
      if (!(v.exposure_end > v.exposure_start)) fail(mpath, where + ": the exposure must end after it starts");
      ds.train.push_back(std::move(v));
    }
    for (size_t i = 0; i < tests.size(); ++i) ds.novel.push_back(view(tests[i], "test[" + std::to_string(i) + "]"));
    ds.events = recording_events(dir, m, W, H, mpath);
    ds.manifest = {{"recording", m}};
    if (m.contains("event_thresholds")) ds.manifest["event_thresholds"] = m["event_thresholds"];
  } catch (const json::exception& e) { fail(mpath, std::string("malformed manifest: ") + e.what()); }
  return ds;
}

}  // namespace evflow::io::detail
