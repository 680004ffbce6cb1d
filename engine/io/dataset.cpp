#include "io/dataset.h"

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

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_image_file(const fs::path& p) {
  const std::string e = lower(p.extension().string());
  return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".exr" || e == ".tif" || e == ".tiff";
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Numeric stems compare as numbers ("2" < "10"), everything else by name.
bool name_less(const fs::path& a, const fs::path& b) {
  const std::string sa = a.stem().string(), sb = b.stem().string();
  if (all_digits(sa) && all_digits(sb)) {
    const std::string ta = sa.substr(std::min(sa.find_first_not_of('0'), sa.size() - 1));
    const std::string tb = sb.substr(std::min(sb.find_first_not_of('0'), sb.size() - 1));
    if (ta.size() != tb.size()) return ta.size() < tb.size();
    if (ta != tb) return ta < tb;
  }
  return a.filename().string() < b.filename().string();
}

std::vector<fs::path> list_files(const fs::path& dir, bool (*keep)(const fs::path&)) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) fail(dir, "folder is missing");
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().filename().string()[0] != '.' && keep(e.path())) out.push_back(e.path());
  if (ec) fail(dir, "cannot list folder: " + ec.message());
  std::sort(out.begin(), out.end(), name_less);
  return out;
}

void require_file(const fs::path& p, const std::string& what) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) fail(p, what + " is missing");
}

// Image read + size check.
Image load_view_image(const fs::path& p, uint32_t w, uint32_t h) {
  require_file(p, "view image");
  Image im = read_image(p);
  if (w && (im.width != w || im.height != h))
    fail(p, "wrong image size " + std::to_string(im.width) + "x" + std::to_string(im.height) + ", expected " +
                std::to_string(w) + "x" + std::to_string(h));
  return im;
}

// Fits the LLFF camera's intrinsics to the actual image size (LLFF files may store the
// full-resolution h, w, f of images that were downsampled).
void fit_camera_to_image(Camera& cam, uint32_t w, uint32_t h, const fs::path& poses, size_t row, const fs::path& image) {
  if (cam.width == w && cam.height == h) return;
  const double sx = double(w) / cam.width, sy = double(h) / cam.height;
  if (std::fabs(cam.height * sx - h) > 1.0 || std::fabs(cam.width * sy - w) > 1.0)  // rounded downsampling
    fail(image, "wrong image size " + std::to_string(w) + "x" + std::to_string(h) + ": row " + std::to_string(row) +
                    " of " + poses.string() + " is for " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
  cam.fx *= sx;
  cam.fy *= sy;
  cam.width = w;
  cam.height = h;
  cam.cx = 0.5 * w;
  cam.cy = 0.5 * h;
}

void set_bounds(Dataset& ds, const PosesBounds& pb) {
  if (pb.near.empty()) return;
  ds.near = *std::min_element(pb.near.begin(), pb.near.end());
  ds.far = *std::max_element(pb.far.begin(), pb.far.end());
}

// ---------------------------------------------------------------------------------- ours
const json& get(const json& j, const char* key, const fs::path& file, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) fail(file, where + ": missing \"" + key + "\"");
  return j.at(key);
}

Dataset load_evflow(const fs::path& dir) {
  const fs::path mpath = dir / "dataset.json";
  Dataset ds;
  ds.layout = "evflow";
  ds.root = dir.string();
  {
    std::ifstream f(mpath);
    if (!f) fail(mpath, "cannot open manifest");
    try {
      ds.manifest = json::parse(f);
    } catch (const std::exception& e) {
      fail(mpath, std::string("malformed JSON: ") + e.what());
    }
  }
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
  } catch (const json::exception& e) {
    fail(mpath, std::string("malformed manifest: ") + e.what());
  }
  return ds;
}

// ---------------------------------------------------------------------------------- E3NeRF
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
                    " images in images/ and " + std::to_string(gts.size()) + " in gt/ (expected training rows then test rows)");
  uint32_t W = 0, H = 0;
  TimeUnit unit = TimeUnit::s;
  bool unit_known = opt.e3nerf_time_unit.has_value();
  if (unit_known) unit = *opt.e3nerf_time_unit;
  std::vector<EventStream> per_view;
  for (size_t i = 0; i < imgs.size(); ++i) {
    View v;
    v.name = imgs[i].stem().string();
    v.blurry = load_view_image(imgs[i], W, H);
    if (!W) { W = v.blurry.width; H = v.blurry.height; }
    v.camera = pb.cameras[i];
    fit_camera_to_image(v.camera, W, H, ppath, i, imgs[i]);
    const fs::path epath = dir / "events" / (v.name + ".txt");
    require_file(epath, "event file of view " + v.name);
    if (!unit_known) {
      std::ifstream f(epath);
      std::string line;
      while (std::getline(f, line)) {
        size_t s = line.find_first_not_of(" \t\r");
        if (s == std::string::npos || line[s] == '#') continue;
        size_t e = line.find_first_of(" \t,", s);
        if (e == std::string::npos) continue;  // a lone token: let the reader complain
        const std::string tok = line.substr(s, e - s);
        unit = tok.find_first_of(".eE") != std::string::npos ? TimeUnit::s : TimeUnit::us;
        unit_known = true;
        break;
      }
    }
    TxtReadOptions o;
    o.unit = unit;
    o.polarity = PolarityCoding::one_else_negative;
    o.width = W;
    o.height = H;
    EventStream ev = read_events_txt(epath, o);
    if (ev.size() == 0) fail(epath, "has no events (the exposure window is first..last event)");
    v.exposure_start = ev.t.front();
    v.exposure_end = ev.t.back();
    per_view.push_back(std::move(ev));
    ds.train.push_back(std::move(v));
  }
  for (size_t i = 0; i < gts.size(); ++i) {
    View v;
    v.name = gts[i].stem().string();
    v.sharp_mid = load_view_image(gts[i], W, H);
    v.camera = pb.cameras[imgs.size() + i];
    fit_camera_to_image(v.camera, W, H, ppath, imgs.size() + i, gts[i]);
    ds.novel.push_back(std::move(v));
  }
  // Merge the per-view streams by time (stable: ties keep view order).
  EventStream& all = ds.events;
  all.width = W;
  all.height = H;
  size_t total = 0;
  for (auto& e : per_view) total += e.size();
  all.reserve(total);
  bool sorted = true;
  for (size_t k = 1; k < per_view.size(); ++k)
    if (per_view[k].t.front() < per_view[k - 1].t.back()) sorted = false;
  if (sorted) {
    for (auto& e : per_view)
      for (size_t i = 0; i < e.size(); ++i) all.push(e.x[i], e.y[i], e.t[i], e.p[i]);
  } else {
    std::vector<std::pair<size_t, size_t>> idx;  // (view, event)
    idx.reserve(total);
    for (size_t k = 0; k < per_view.size(); ++k)
      for (size_t i = 0; i < per_view[k].size(); ++i) idx.emplace_back(k, i);
    std::stable_sort(idx.begin(), idx.end(), [&](auto a, auto b) { return per_view[a.first].t[a.second] < per_view[b.first].t[b.second]; });
    for (auto [k, i] : idx) all.push(per_view[k].x[i], per_view[k].y[i], per_view[k].t[i], per_view[k].p[i]);
  }
  set_bounds(ds, pb);
  ds.manifest = {{"layout", "e3nerf"},
                 {"resolution", {W, H}},
                 {"event_time_unit", to_string(unit)},
                 {"exposure", "first..last event of events/<view>.txt"},
                 {"train_views", ds.train.size()},
                 {"novel_views", ds.novel.size()}};
  return ds;
}

// ---------------------------------------------------------------------------------- EBAD-NeRF
Dataset load_ebad(const fs::path& dir, const LoadOptions& opt) {
  Dataset ds;
  ds.layout = "ebad";
  ds.root = dir.string();
  const int every = std::max(1, opt.ebad_test_every);
  const fs::path ppath = dir / "poses_bounds.npy";
  require_file(ppath, "poses file");
  PosesBounds pb = read_poses_bounds(ppath);
  const size_t N = pb.rows.size();
  std::vector<size_t> train_idx, test_idx;
  for (size_t i = 0; i < N; ++i) (i % size_t(every) == 0 ? test_idx : train_idx).push_back(i);
  if (every == 1) { train_idx.swap(test_idx); }  // degenerate: no hold-out
  const auto imgs = list_files(dir / "images", is_image_file);
  // images/ holds either every view or only the training views; likewise images_gt_blur/ (when
  // present); images_gt_novel/ holds either every view or only the test views.
  auto pick = [&](const std::vector<fs::path>& files, const std::vector<size_t>& subset, const fs::path& folder) {
    std::vector<fs::path> out;
    if (files.size() == N) for (size_t i : subset) out.push_back(files[i]);
    else if (files.size() == subset.size()) out = files;
    else
      fail(folder, "has " + std::to_string(files.size()) + " images, but " + ppath.string() + " has " + std::to_string(N) +
                       " poses (" + std::to_string(subset.size()) + " expected here: every " + std::to_string(every) +
                       "th view is a test view)");
    return out;
  };
  const auto train_imgs = pick(imgs, train_idx, dir / "images");
  std::vector<fs::path> sharp_imgs;
  std::error_code ec;
  if (fs::is_directory(dir / "images_gt_blur", ec))
    sharp_imgs = pick(list_files(dir / "images_gt_blur", is_image_file), train_idx, dir / "images_gt_blur");
  std::vector<fs::path> novel_imgs;
  if (!test_idx.empty()) novel_imgs = pick(list_files(dir / "images_gt_novel", is_image_file), test_idx, dir / "images_gt_novel");
  uint32_t W = 0, H = 0;
  for (size_t k = 0; k < train_idx.size(); ++k) {
    View v;
    v.name = train_imgs[k].stem().string();
    v.blurry = load_view_image(train_imgs[k], W, H);
    if (!W) { W = v.blurry.width; H = v.blurry.height; }
    if (!sharp_imgs.empty()) v.sharp_mid = load_view_image(sharp_imgs[k], W, H);
    v.camera = pb.cameras[train_idx[k]];
    fit_camera_to_image(v.camera, W, H, ppath, train_idx[k], train_imgs[k]);
    v.exposure_start = 0;  // EBAD-NeRF events are pre-binned per view: normalised exposure
    v.exposure_end = 1;
    ds.train.push_back(std::move(v));
  }
  for (size_t k = 0; k < novel_imgs.size(); ++k) {
    View v;
    v.name = novel_imgs[k].stem().string();
    v.sharp_mid = load_view_image(novel_imgs[k], W, H);
    v.camera = pb.cameras[test_idx[k]];
    fit_camera_to_image(v.camera, W, H, ppath, test_idx[k], novel_imgs[k]);
    ds.novel.push_back(std::move(v));
  }
  const fs::path epath = dir / "events.npy";
  NpyArray a = read_npy(epath);
  if (a.shape.size() != 3) fail(epath, "event counts must have shape [views, bins, H*W], found rank " + std::to_string(a.shape.size()));
  if (a.shape[2] != size_t(W) * H)
    fail(epath, "has " + std::to_string(a.shape[2]) + " pixels per bin, the images have " + std::to_string(W) + "x" +
                    std::to_string(H) + " = " + std::to_string(size_t(W) * H));
  if (a.dtype == DType::b1) fail(epath, "event counts must be numbers, found bool");
  std::vector<float> counts = a.to_float();
  const size_t bins = a.shape[1], hw = a.shape[2];
  if (a.shape[0] == train_idx.size()) {
    ds.event_counts = std::move(counts);
  } else if (a.shape[0] == N) {
    ds.event_counts.reserve(train_idx.size() * bins * hw);
    for (size_t i : train_idx)
      ds.event_counts.insert(ds.event_counts.end(), counts.begin() + i * bins * hw, counts.begin() + (i + 1) * bins * hw);
  } else {
    fail(epath, "has event counts for " + std::to_string(a.shape[0]) + " views; expected " + std::to_string(train_idx.size()) +
                    " (training views) or " + std::to_string(N) + " (all views)");
  }
  for (float c : ds.event_counts)
    if (!std::isfinite(c)) fail(epath, "has a non-finite event count");
  ds.event_counts_shape = {train_idx.size(), bins, hw};
  ds.events.width = W;
  ds.events.height = H;
  set_bounds(ds, pb);
  json test = json::array();
  for (size_t i : test_idx) test.push_back(i);
  ds.manifest = {{"layout", "ebad"},
                 {"resolution", {W, H}},
                 {"test_every", every},
                 {"test_rows", test},
                 {"event_bins", bins},
                 {"exposure", "normalised [0, 1]; events are per-view counts"}};
  return ds;
}

// ------------------------------------------------------------------- plain sharp LLFF
// images/ + poses_bounds.npy, no events: every image is both the training input and its own
// sharp ground truth; every `test_every`-th view (0, 8, 16, ...) is held out as a novel view.
Dataset load_llff_sharp(const fs::path& dir, const LoadOptions& opt) {
  Dataset ds;
  ds.layout = "llff";
  ds.root = dir.string();
  const fs::path ppath = dir / "poses_bounds.npy";
  PosesBounds pb = read_poses_bounds(ppath);
  set_bounds(ds, pb);
  const auto imgs = list_files(dir / "images", is_image_file);
  if (imgs.size() != pb.rows.size())
    fail(dir / "images", "has " + std::to_string(imgs.size()) + " images, but " + ppath.string() + " has " +
                             std::to_string(pb.rows.size()) + " poses");
  const int every = std::max(1, opt.ebad_test_every);
  uint32_t W = 0, H = 0;
  for (size_t i = 0; i < imgs.size(); ++i) {
    View v;
    v.name = imgs[i].stem().string();
    Image im = load_view_image(imgs[i], W, H);
    if (!W) { W = im.width; H = im.height; }
    v.camera = pb.cameras[i];
    fit_camera_to_image(v.camera, W, H, ppath, i, imgs[i]);
    v.sharp_mid = im;
    if (every > 1 && i % size_t(every) == 0) {
      ds.novel.push_back(std::move(v));
    } else {
      v.blurry = std::move(im);
      ds.train.push_back(std::move(v));
    }
  }
  if (ds.train.empty()) fail(dir, "no training views");
  ds.manifest = {{"layout", "llff"}, {"test_every", every}};
  return ds;
}

// ------------------------------------------------------------- NeRF-synthetic (Blender)
// transforms_{train,test}.json: camera_angle_x (horizontal field of view), frames with
// file_path (extension optional) and transform_matrix (camera-to-world, OpenGL axes: x right,
// y up, z back; converted to OpenCV by flipping y and z). Alpha is dropped (the images' RGB
// is black where transparent, so train with the default black background).
Dataset load_nerf_synthetic(const fs::path& dir) {
  Dataset ds;
  ds.layout = "nerf-synthetic";
  ds.root = dir.string();
  auto load_split = [&](const fs::path& file, std::vector<View>& out, bool train) {
    std::ifstream f(file);
    if (!f) fail(file, "cannot open");
    json j;
    try { f >> j; } catch (const std::exception& e) { fail(file, std::string("malformed JSON: ") + e.what()); }
    const double fov = get(j, "camera_angle_x", file, "top level").get<double>();
    const json& frames = get(j, "frames", file, "top level");
    if (!frames.is_array() || frames.empty()) fail(file, "\"frames\" must be a non-empty array");
    for (size_t k = 0; k < frames.size(); ++k) {
      const std::string where = "frame " + std::to_string(k);
      fs::path img = dir / get(frames[k], "file_path", file, where).get<std::string>();
      if (!img.has_extension() || !fs::exists(img)) img += ".png";
      Image im = load_view_image(img, 0, 0);
      const json& M = get(frames[k], "transform_matrix", file, where);
      if (!M.is_array() || M.size() < 3) fail(file, where + ": transform_matrix must be 4x4");
      double c2w[3][4];
      for (int r = 0; r < 3; ++r) {
        if (!M[r].is_array() || M[r].size() != 4) fail(file, where + ": transform_matrix must be 4x4");
        for (int c = 0; c < 4; ++c) {
          c2w[r][c] = M[r][c].get<double>();
          if (!std::isfinite(c2w[r][c])) fail(file, where + ": transform_matrix is not finite");
        }
      }
      View v;
      v.name = img.stem().string();
      Camera& cam = v.camera;
      cam.width = im.width;
      cam.height = im.height;
      cam.fx = cam.fy = 0.5 * im.width / std::tan(0.5 * fov);
      cam.cx = 0.5 * im.width;
      cam.cy = 0.5 * im.height;
      // OpenCV rotation columns: x, -y, -z of the OpenGL camera; world_to_camera = its transpose.
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) cam.R[c * 3 + r] = c2w[r][c] * (c == 0 ? 1.0 : -1.0);
      for (int r = 0; r < 3; ++r) cam.t[r] = -(cam.R[r * 3] * c2w[0][3] + cam.R[r * 3 + 1] * c2w[1][3] + cam.R[r * 3 + 2] * c2w[2][3]);
      v.sharp_mid = im;
      if (train) v.blurry = std::move(im);
      out.push_back(std::move(v));
    }
  };
  load_split(dir / "transforms_train.json", ds.train, true);
  std::error_code ec;
  if (fs::exists(dir / "transforms_test.json", ec)) load_split(dir / "transforms_test.json", ds.novel, false);
  ds.near = 2.0;  // the Blender scenes' conventional bounds
  ds.far = 6.0;
  ds.manifest = {{"layout", "nerf-synthetic"}};
  return ds;
}

}  // namespace

Dataset load_dataset(const fs::path& dir, const LoadOptions& opt) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) fail(dir, "dataset folder is missing");
  if (fs::exists(dir / "dataset.json", ec)) return load_evflow(dir);
  if (fs::exists(dir / "events.npy", ec)) return load_ebad(dir, opt);
  if (fs::is_directory(dir / "events", ec) && fs::is_directory(dir / "gt", ec)) return load_e3nerf(dir, opt);
  if (fs::exists(dir / "transforms_train.json", ec)) return load_nerf_synthetic(dir);
  if (fs::exists(dir / "poses_bounds.npy", ec) && fs::is_directory(dir / "images", ec)) return load_llff_sharp(dir, opt);
  fail(dir, "unrecognised dataset layout: expected dataset.json (EvFlow), events.npy (EBAD-NeRF), events/ + gt/ (E3NeRF), "
            "transforms_train.json (NeRF-synthetic) or images/ + poses_bounds.npy (LLFF)");
}

void write_evflow_dataset(const Dataset& ds, const fs::path& dir, const WriteOptions& opt) {
  auto bad = [&](const std::string& what) { return std::invalid_argument(dir.string() + ": write_evflow_dataset: " + what); };
  if (ds.train.empty()) throw bad("no training views");
  if (opt.image_ext != ".png" && opt.image_ext != ".exr") throw bad("image_ext must be .png or .exr");
  const uint32_t W = ds.train[0].blurry.width, H = ds.train[0].blurry.height;
  std::vector<std::string> names;
  auto check = [&](const View& v, const Image* im, const char* kind) {
    if (v.name.empty() || v.name.find_first_of("/\\") != std::string::npos || v.name[0] == '.')
      throw bad("bad view name '" + v.name + "'");
    if (std::find(names.begin(), names.end(), v.name) != names.end()) throw bad("duplicate view name '" + v.name + "'");
    names.push_back(v.name);
    if (!im || im->empty()) throw bad(std::string(kind) + " view '" + v.name + "' has no image");
    if (im->width != W || im->height != H) throw bad("view '" + v.name + "' image size differs from the first view's");
    if (v.camera.width != W || v.camera.height != H) throw bad("view '" + v.name + "' camera size differs from its image");
  };
  for (const View& v : ds.train) {
    check(v, &v.blurry, "training");
    if (v.sharp_mid && (v.sharp_mid->width != W || v.sharp_mid->height != H)) throw bad("view '" + v.name + "' sharp image size");
  }
  names.clear();
  for (const View& v : ds.novel) check(v, v.sharp_mid ? &*v.sharp_mid : nullptr, "novel");
  if (!ds.event_counts.empty() &&
      (ds.event_counts_shape.size() != 3 || ds.event_counts_shape[0] * ds.event_counts_shape[1] * ds.event_counts_shape[2] != ds.event_counts.size()))
    throw bad("event_counts does not match event_counts_shape");

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
    json e = {{"name", v.name}, {"image", img}, {"exposure", {v.exposure_start, v.exposure_end}}, {"intrinsics", intr(v.camera)}};
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
  if (ev.width == 0 && ev.height == 0 && ev.size() == 0) { ev.width = W; ev.height = H; }
  if (ev.width != W || ev.height != H) throw bad("event sensor size differs from the image size");
  write_events_h5(dir / "events.h5", ev, es, ee);
  m["events"] = "events.h5";
  if (!ds.event_counts.empty()) {
    write_npy(dir / "event_counts.npy", ds.event_counts_shape, ds.event_counts);
    m["event_counts"] = "event_counts.npy";
  } else {
    m.erase("event_counts");
  }
  const std::string text = m.dump(2) + "\n";
  write_file_atomic(dir / "dataset.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    f.close();
    if (!f) throw std::runtime_error((dir / "dataset.json").string() + ": write error");
  });
}

}  // namespace evflow::io
