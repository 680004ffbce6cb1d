// Plain sharp multi-view data for training without events: LLFF folders and NeRF-synthetic.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "io/dataset.h"
#include "io/image.h"
#include "io/llff.h"

using namespace evflow;
namespace fs = std::filesystem;

static io::Image flat_image(uint32_t w, uint32_t h, float v) {
  io::Image im;
  im.width = w;
  im.height = h;
  im.channels = 3;
  im.data.assign(size_t(w) * h * 3, v);
  return im;
}

TEST_CASE("datasets: a plain LLFF folder loads as sharp views with every 8th held out", "[io][train]") {
  fs::path dir = fs::temp_directory_path() / "evf_llff_sharp";
  fs::remove_all(dir);
  std::vector<Camera> cams;
  for (int i = 0; i < 10; ++i) {
    cams.push_back(Camera::look_at(40, 30, 50.0, {0.1 * i, 0, 0}, {0, 0, 5}, {0, -1, 0}));
    io::write_png(dir / "images" / ("img" + std::to_string(100 + i) + ".png"), flat_image(40, 30, 0.05f * i));
  }
  io::write_poses_bounds(dir / "poses_bounds.npy", cams, std::vector<double>(10, 1.0), std::vector<double>(10, 9.0));
  io::Dataset d = io::load_dataset(dir);
  REQUIRE(d.layout == "llff");
  REQUIRE(d.train.size() == 8);
  REQUIRE(d.novel.size() == 2);
  REQUIRE(d.novel[0].name == "img100");
  REQUIRE(d.novel[1].name == "img108");
  REQUIRE(d.train[0].sharp_mid.has_value());
  REQUIRE(d.train[0].camera.t[0] == Approx(cams[1].t[0]).margin(1e-9));
  REQUIRE(d.near == Approx(1.0));
  // A missing image is an error naming the folder.
  fs::remove(dir / "images" / "img105.png");
  REQUIRE_THROWS_WITH(io::load_dataset(dir), Catch::Contains("images") && Catch::Contains("9 images"));
  fs::remove_all(dir);
}

TEST_CASE("datasets: NeRF-synthetic transforms.json converts OpenGL cameras to ours", "[io][train]") {
  fs::path dir = fs::temp_directory_path() / "evf_nerf_synth";
  fs::remove_all(dir);
  fs::create_directories(dir / "train");
  io::write_png(dir / "train" / "r_0.png", flat_image(64, 48, 0.5f));
  // OpenGL camera at (1, 2, 4) looking down -z (identity rotation).
  std::ofstream(dir / "transforms_train.json") << R"({"camera_angle_x": 0.9,
    "frames": [{"file_path": "./train/r_0", "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,4],[0,0,0,1]]}]})";
  io::Dataset d = io::load_dataset(dir);
  REQUIRE(d.layout == "nerf-synthetic");
  REQUIRE(d.train.size() == 1);
  const Camera& c = d.train[0].camera;
  REQUIRE(c.fx == Approx(32.0 / std::tan(0.45)));
  // The world point (1, 2, 0) lies straight ahead at depth 4; (1, 3, 0) is above it: y up in
  // the world is y down in the image.
  auto project = [&](double x, double y, double z) {
    double p[3];
    for (int r = 0; r < 3; ++r) p[r] = c.R[r * 3] * x + c.R[r * 3 + 1] * y + c.R[r * 3 + 2] * z + c.t[r];
    return std::array<double, 3>{c.fx * p[0] / p[2] + c.cx, c.fy * p[1] / p[2] + c.cy, p[2]};
  };
  auto a = project(1, 2, 0), b = project(1, 3, 0);
  REQUIRE(a[0] == Approx(32.0));
  REQUIRE(a[1] == Approx(24.0));
  REQUIRE(a[2] == Approx(4.0));
  REQUIRE(b[1] < a[1]);
  std::ofstream(dir / "transforms_train.json") << R"({"frames": []})";
  REQUIRE_THROWS_WITH(io::load_dataset(dir),
                      Catch::Contains("transforms_train.json") && Catch::Contains("camera_angle_x"));
  fs::remove_all(dir);
}
