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

namespace {

// Which rows are test views: every `every`th, from row 0 (every = 1: none held out).
void split_rows(size_t n, int every, std::vector<size_t>& train, std::vector<size_t>& test) {
  for (size_t i = 0; i < n; ++i) (i % size_t(every) == 0 ? test : train).push_back(i);
  if (every == 1) train.swap(test);  // degenerate: no hold-out
}

// The files of `subset`'s rows: `files` holds either every view or exactly the subset.
std::vector<fs::path> pick(const std::vector<fs::path>& files, const std::vector<size_t>& subset,
                           const fs::path& folder, size_t rows, int every, const fs::path& ppath) {
  if (files.size() == subset.size()) return files;
  if (files.size() != rows)
    fail(folder, "has " + std::to_string(files.size()) + " images, but " + ppath.string() + " has " +
                     std::to_string(rows) + " poses (" + std::to_string(subset.size()) + " expected here: every " +
                     std::to_string(every) + "th view is a test view)");
  std::vector<fs::path> out;
  for (size_t i : subset) out.push_back(files[i]);
  return out;
}

// A view's camera from pose row `row`, fitted to the image size (W x H fixed by the first image).
View make_view(const fs::path& img, const Image& image, const PosesBounds& pb, size_t row, const fs::path& ppath,
               uint32_t& W, uint32_t& H) {
  View v;
  v.name = img.stem().string();
  if (!W) {
    W = image.width;
    H = image.height;
  }
  v.camera = pb.cameras[row];
  fit_camera_to_image(v.camera, W, H, ppath, row, img);
  return v;
}

// events.npy: counts [views, bins, H*W] for the training views or for every view. Returns the bins.
size_t read_counts(const fs::path& epath, Dataset& ds, const std::vector<size_t>& train_idx, size_t rows, uint32_t W,
                   uint32_t H) {
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
  } else if (a.shape[0] == rows) {
    ds.event_counts.reserve(train_idx.size() * bins * hw);
    for (size_t i : train_idx)
      ds.event_counts.insert(ds.event_counts.end(), counts.begin() + i * bins * hw,
                             counts.begin() + (i + 1) * bins * hw);
  } else {
    fail(epath, "has event counts for " + std::to_string(a.shape[0]) + " views; expected " +
                    std::to_string(train_idx.size()) + " (training views) or " + std::to_string(rows) + " (all views)");
  }
  for (float c : ds.event_counts)
    if (!std::isfinite(c)) fail(epath, "has a non-finite event count");
  ds.event_counts_shape = {train_idx.size(), bins, hw};
  return bins;
}

}  // namespace

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
  split_rows(N, every, train_idx, test_idx);
  // images/ holds either every view or only the training views; likewise images_gt_blur/ (when
  // present); images_gt_novel/ holds either every view or only the test views.
  auto files = [&](const char* folder, const std::vector<size_t>& subset) {
    return pick(list_files(dir / folder, is_image_file), subset, dir / folder, N, every, ppath);
  };
  const auto train_imgs = files("images", train_idx);
  std::error_code ec;
  const auto sharp_imgs =
      fs::is_directory(dir / "images_gt_blur", ec) ? files("images_gt_blur", train_idx) : std::vector<fs::path>{};
  const auto novel_imgs = test_idx.empty() ? std::vector<fs::path>{} : files("images_gt_novel", test_idx);
  uint32_t W = 0, H = 0;
  for (size_t k = 0; k < train_idx.size(); ++k) {
    Image blurry = load_view_image(train_imgs[k], W, H);
    View v = make_view(train_imgs[k], blurry, pb, train_idx[k], ppath, W, H);
    v.blurry = std::move(blurry);
    if (!sharp_imgs.empty()) v.sharp_mid = load_view_image(sharp_imgs[k], W, H);
    v.exposure_start = 0;  // EBAD-NeRF events are pre-binned per view: normalised exposure
    v.exposure_end = 1;
    ds.train.push_back(std::move(v));
  }
  for (size_t k = 0; k < novel_imgs.size(); ++k) {
    Image sharp = load_view_image(novel_imgs[k], W, H);
    View v = make_view(novel_imgs[k], sharp, pb, test_idx[k], ppath, W, H);
    v.sharp_mid = std::move(sharp);
    ds.novel.push_back(std::move(v));
  }
  const size_t bins = read_counts(dir / "events.npy", ds, train_idx, N, W, H);
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
