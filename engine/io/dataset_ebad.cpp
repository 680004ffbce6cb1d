// Reader of EBAD-NeRF folders (events.npy); docs/datasets.md.
#include "io/dataset_formats.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "io/llff.h"
#include "io/npy.h"

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

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
    if (files.size() == N)
      for (size_t i : subset) out.push_back(files[i]);
    else if (files.size() == subset.size())
      out = files;
    else
      fail(folder, "has " + std::to_string(files.size()) + " images, but " + ppath.string() + " has " +
                       std::to_string(N) + " poses (" + std::to_string(subset.size()) + " expected here: every " +
                       std::to_string(every) + "th view is a test view)");
    return out;
  };
  const auto train_imgs = pick(imgs, train_idx, dir / "images");
  std::vector<fs::path> sharp_imgs;
  std::error_code ec;
  if (fs::is_directory(dir / "images_gt_blur", ec))
    sharp_imgs = pick(list_files(dir / "images_gt_blur", is_image_file), train_idx, dir / "images_gt_blur");
  std::vector<fs::path> novel_imgs;
  if (!test_idx.empty())
    novel_imgs = pick(list_files(dir / "images_gt_novel", is_image_file), test_idx, dir / "images_gt_novel");
  uint32_t W = 0, H = 0;
  for (size_t k = 0; k < train_idx.size(); ++k) {
    View v;
    v.name = train_imgs[k].stem().string();
    v.blurry = load_view_image(train_imgs[k], W, H);
    if (!W) {
      W = v.blurry.width;
      H = v.blurry.height;
    }
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
  if (a.shape.size() != 3)
    fail(epath, "event counts must have shape [views, bins, H*W], found rank " + std::to_string(a.shape.size()));
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
      ds.event_counts.insert(ds.event_counts.end(), counts.begin() + i * bins * hw,
                             counts.begin() + (i + 1) * bins * hw);
  } else {
    fail(epath, "has event counts for " + std::to_string(a.shape[0]) + " views; expected " +
                    std::to_string(train_idx.size()) + " (training views) or " + std::to_string(N) + " (all views)");
  }
  for (float c : ds.event_counts)
    if (!std::isfinite(c)) fail(epath, "has a non-finite event count");
  ds.event_counts_shape = {train_idx.size(), bins, hw};
  ds.events.width = W;
  ds.events.height = H;
  set_bounds(ds, pb);
  json test = json::array();
  for (size_t i : test_idx) test.push_back(i);
  ds.manifest = {{"layout", "ebad"},    {"resolution", {W, H}},
                 {"test_every", every}, {"test_rows", test},
                 {"event_bins", bins},  {"exposure", "normalised [0, 1]; events are per-view counts"}};
  return ds;
}

}  // namespace evflow::io::detail
