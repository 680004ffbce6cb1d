// engine/io/colmap_model: COLMAP's text model as `evflow poses` reads it; the sparse points of our
// layout and the trainer's init=points.
#include <unistd.h>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "camera/se3.h"
#include "cli_helpers.h"
#include "io/colmap_model.h"
#include "io/dataset.h"
#include "io/dataset_writer.h"
#include "train/training_data.h"

using namespace evflow;
using evflow::test::fresh_dir;
namespace fs = std::filesystem;

namespace {

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p) << s; }

// The rotation vector of the second image's pose, and its quaternion (w, x, y, z) as text.
const lie::Vec3 kPhi{0.3, -0.5, 0.8};
std::string quaternion_text() {
  const double th = std::sqrt(kPhi[0] * kPhi[0] + kPhi[1] * kPhi[1] + kPhi[2] * kPhi[2]);
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g %.17g", std::cos(th / 2), std::sin(th / 2) * kPhi[0] / th,
                std::sin(th / 2) * kPhi[1] / th, std::sin(th / 2) * kPhi[2] / th);
  return buf;
}

// A model of two images, the second rotated by kPhi and without 2D points (its second line is
// empty, as COLMAP writes it).
void write_model(const fs::path& d, const std::string& camera_line) {
  write_text(d / "cameras.txt", "# Camera list\n# CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n" + camera_line + "\n");
  write_text(d / "images.txt",
             "# Image list\n# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
             "1 1 0 0 0 0.5 -1 2 1 t000_a b.png\n"
             "10 20 1 0 -1\n"
             "2 " +
                 quaternion_text() +
                 " 0 0 3 1 t001_c.png\n"
                 "\n");
  write_text(d / "points3D.txt",
             "# 3D point list\n"
             "7 0.5 1.5 -2 255 128 0 0.75 1 0 2 0\n"
             "8 1 2 3 10 20 30 0.25 2 1\n");
}

}  // namespace

TEST_CASE("read_colmap_text: poses, intrinsics, points and tracks", "[io][colmap]") {
  const fs::path d = fresh_dir("evflow_colmap_model");
  write_model(d, "1 PINHOLE 64 48 50 51 32.5 24.25");
  const io::ColmapModel m = io::read_colmap_text(d);
  REQUIRE(m.images.size() == 2);
  CHECK(m.images[0].id == 1);
  CHECK(m.images[0].name == "t000_a b.png");  // names may hold spaces
  CHECK(m.images[0].camera.t == std::array<double, 3>{0.5, -1, 2});
  CHECK(m.images[0].camera.R == lie::identity3());
  const Camera& c = m.images[1].camera;
  CHECK(c.width == 64);
  CHECK(c.height == 48);
  CHECK(c.fx == 50);
  CHECK(c.fy == 51);
  CHECK(c.cx == 32.5);
  CHECK(c.cy == 24.25);
  const lie::Mat3 R = lie::so3_exp(kPhi);
  for (int i = 0; i < 9; ++i) CHECK(c.R[i] == Approx(R[i]).margin(1e-12));
  REQUIRE(m.points.size() == 2);
  CHECK(m.points[0].xyz == std::array<double, 3>{0.5, 1.5, -2});
  CHECK(m.points[0].rgb == std::array<uint8_t, 3>{255, 128, 0});
  CHECK(m.points[0].error == 0.75);
  CHECK(m.points[0].image_ids == std::vector<uint32_t>{1, 2});
  CHECK(m.points[1].image_ids == std::vector<uint32_t>{2});
  fs::remove_all(d);
}

TEST_CASE("read_colmap_text: other camera models and malformed lines are refused, naming file and line",
          "[io][colmap]") {
  const fs::path d = fresh_dir("evflow_colmap_bad");
  write_model(d, "1 SIMPLE_RADIAL 64 48 50 32 24 0.01");
  CHECK_THROWS_WITH(io::read_colmap_text(d), Catch::Contains("cameras.txt:3") && Catch::Contains("SIMPLE_RADIAL"));
  write_model(d, "2 PINHOLE 64 48 50 51 32 24");
  CHECK_THROWS_WITH(io::read_colmap_text(d), Catch::Contains("images.txt:3") && Catch::Contains("camera 1"));
  write_model(d, "1 PINHOLE 64 48 50 51 32 24");
  write_text(d / "points3D.txt", "7 0.5 1.5 -2 255 128 0 0.75 1 x\n");
  CHECK_THROWS_WITH(io::read_colmap_text(d), Catch::Contains("points3D.txt:1") && Catch::Contains("track"));
  fs::remove(d / "points3D.txt");
  CHECK_THROWS_WITH(io::read_colmap_text(d), Catch::Contains("points3D.txt") && Catch::Contains("cannot open"));
  fs::remove_all(d);
}

TEST_CASE("sparse points round-trip through our layout and init=points starts from them", "[io][colmap][train]") {
  io::Dataset ds;
  io::View v;
  v.name = "v0";
  v.blurry.width = 8;
  v.blurry.height = 6;
  v.blurry.channels = 3;
  v.blurry.data.assign(8 * 6 * 3, 0.5f);
  v.camera.width = 8;
  v.camera.height = 6;
  v.camera.fx = v.camera.fy = 10;
  v.camera.cx = 4;
  v.camera.cy = 3;
  v.exposure_end = 0.01;
  ds.train.push_back(v);
  ds.near = 1;
  ds.far = 10;
  // Five points: four at the corners of a unit square in z = 5, one at its centre.
  ds.points = {0, 0, 5, 1, 0, 0, 1, 0, 5, 0, 1, 0, 0, 1, 5, 0, 0, 1, 1, 1, 5, 1, 1, 1, 0.5f, 0.5f, 5, 0.5f, 0.5f, 0.5f};
  const fs::path d = fresh_dir("evflow_points_layout");
  io::write_evflow_dataset(ds, d);
  const io::Dataset back = io::load_dataset(d);
  CHECK(back.points == ds.points);

  TrainConfig cfg;
  cfg.sh_degree = 0;
  cfg.init = InitSource::Points;
  const GaussianCloud c = initial_cloud(back, cfg);
  REQUIRE(c.size() == 5);
  CHECK(c.means[4 * 3] == 0.5f);
  CHECK(c.means[4 * 3 + 2] == 5.0f);
  // The centre's 3 nearest neighbours are corners at sqrt(0.5); a corner's are the centre and two
  // corners: (sqrt(0.5) + 1 + 1) / 3.
  CHECK(std::exp(c.log_scales[4 * 3]) == Approx(std::sqrt(0.5)).epsilon(1e-6));
  CHECK(std::exp(c.log_scales[0]) == Approx((std::sqrt(0.5) + 2) / 3).epsilon(1e-6));
  CHECK(c.sh[0] * 0.28209479177387814 + 0.5 == Approx(1.0).epsilon(1e-6));  // red corner
  CHECK(c.sh[1] * 0.28209479177387814 + 0.5 == Approx(0.0).margin(1e-6));

  io::Dataset none = back;
  none.points.clear();
  CHECK_THROWS_WITH(initial_cloud(none, cfg), Catch::Contains("no sparse points"));
  fs::remove_all(d);
}
