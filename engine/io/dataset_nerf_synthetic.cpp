// Reader of NeRF-synthetic (Blender) folders (transforms_*.json); docs/datasets.md.
#include "io/dataset_formats.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

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
    try {
      f >> j;
    } catch (const std::exception& e) { fail(file, std::string("malformed JSON: ") + e.what()); }
    const double fov = get(j, "camera_angle_x", file, "top level").get<double>();
    const json& frames = get(j, "frames", file, "top level");
    if (!frames.is_array() || frames.empty()) fail(file, "\"frames\" must be a non-empty array");
    for (size_t k = 0; k < frames.size(); ++k) {
      const std::string where = "frame " + std::to_string(k);
      fs::path img = dir / get(frames[k], "file_path", file, where).get<std::string>();
      if (!img.has_extension() || !fs::exists(img)) img += ".png";
      // A missing or bad image is named with the manifest and the frame that points at it (an
      // absolute file_path leaves the dataset folder out of the image's own path).
      Image im;
      try {
        im = load_view_image(img, 0, 0);
      } catch (const std::runtime_error& e) { fail(file, where + ": " + e.what()); }
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
      for (int r = 0; r < 3; ++r)
        cam.t[r] = -(cam.R[r * 3] * c2w[0][3] + cam.R[r * 3 + 1] * c2w[1][3] + cam.R[r * 3 + 2] * c2w[2][3]);
      v.sharp_mid = im;
      if (train) v.blurry = std::move(im);
      out.push_back(std::move(v));
    }
  };
  // A value of the wrong JSON type (a string for camera_angle_x) is an error naming the file.
  auto load_checked = [&](const fs::path& file, std::vector<View>& out, bool train) {
    try {
      load_split(file, out, train);
    } catch (const json::exception& e) { fail(file, std::string("malformed file: ") + e.what()); }
  };
  load_checked(dir / "transforms_train.json", ds.train, true);
  std::error_code ec;
  if (fs::exists(dir / "transforms_test.json", ec)) load_checked(dir / "transforms_test.json", ds.novel, false);
  ds.near = 2.0;  // the Blender scenes' conventional bounds
  ds.far = 6.0;
  ds.manifest = {{"layout", "nerf-synthetic"}};
  return ds;
}

}  // namespace evflow::io::detail
