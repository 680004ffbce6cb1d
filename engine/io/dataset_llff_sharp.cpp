// Reader of plain sharp LLFF folders (images/ + poses_bounds.npy); docs/datasets.md.
#include "io/dataset_formats.h"

#include <algorithm>
#include <stdexcept>

#include "io/llff.h"

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

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
    if (!W) {
      W = im.width;
      H = im.height;
    }
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

}  // namespace evflow::io::detail
