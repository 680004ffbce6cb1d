// `evflow render`: splats from a camera file render exactly as the engine renders them, and a
// run's exposure path holds the image `evflow eval` scores at mid-exposure.
#include <sys/wait.h>
#include <unistd.h>
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "gpu_fixture.h"
#include "io/camera_json.h"
#include "io/dataset.h"
#include "io/ply_splats.h"
#include "metrics/srgb_metrics.h"
#include "reference/random_scene.h"
#include "splat/rasterizer.h"
#include "train/checkpoint.h"

using namespace evflow;
using namespace evflow::test;
namespace fs = std::filesystem;

namespace {

// Runs an evflow command that must succeed; its output shows when it does not.
void expect_ok(const fs::path& dir, const std::string& args) {
  std::string out;
  const int rc = run_evflow(dir, args, out);
  INFO(args << "\n" << out);
  REQUIRE(rc == 0);
}

}  // namespace

TEST_CASE("render: a PLY from a camera file gives the engine's own render, byte for byte", "[render][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_render_ply");
  const Camera c0 = reference::test_camera(72, 56);
  Camera c1 = Camera::look_at(40, 30, 50.0, {0.3, -0.2, -1.5}, {0, 0, 2.5}, {0, -1, 0});
  const GaussianCloud cloud = reference::random_scene(5, 300, 1, c0);
  io::write_ply(dir / "s.ply", cloud);
  {
    std::ofstream f(dir / "cams.json");
    f << nlohmann::json{{"cameras", {io::camera_to_json(c0), io::camera_to_json(c1)}}}.dump(2);
  }
  expect_ok(dir, "render s.ply --camera cams.json --out r");

  auto& ctx = gpu_context();
  GaussianBuffers params(ctx, cloud.size(), cloud.sh_degree, "p_");
  params.upload(cloud);
  Rasterizer r(ctx);
  const Camera cams[2] = {c0, c1};
  for (int i = 0; i < 2; ++i) {
    RenderState st = r.forward(params, cams[i], RenderSettings{});
    const auto img = metrics::quantise_srgb(st.outputs().rgb.read<float>(size_t(3) * cams[i].width * cams[i].height),
                                            cams[i].width, cams[i].height, 3);
    size_t lit = 0;
    for (uint8_t b : img.data) lit += b > 8;
    REQUIRE(lit > img.data.size() / 20);  // not a blank image
    const fs::path expect = dir / ("expect_" + std::to_string(i) + ".png");
    metrics::write_png(expect, img);
    const fs::path got = dir / "r" / ("camera_00" + std::to_string(i) + ".png");
    REQUIRE(fs::exists(got));
    CHECK(slurp(got) == slurp(expect));
  }
  require_no_validation_messages();

  std::string out;
  // Bad camera files and options: clear errors naming what is wrong.
  {
    std::ofstream f(dir / "bad.json");
    auto j = io::camera_to_json(c0);
    j.erase("fx");
    f << nlohmann::json::array({io::camera_to_json(c0), j}).dump();
  }
  CHECK(run_evflow(dir, "render s.ply --camera bad.json --out r2", out) != 0);
  CHECK(out.find("bad.json: camera 1: 'fx'") != std::string::npos);
  CHECK(!fs::exists(dir / "r2"));
  CHECK(run_evflow(dir, "render s.ply --camera cams.json --path orbit --out r3", out) != 0);
  CHECK(out.find("exclude") != std::string::npos);
  CHECK(run_evflow(dir, "render s.ply --path exposure --out r4", out) != 0);
  CHECK(out.find("training run folder") != std::string::npos);

  // The same camera file and splats feed the rasterizer benchmark: its first camera's size, the
  // file's Gaussians, and the intersections of that very view.
  REQUIRE(run_evflow(dir, "bench raster --camera cams.json --splats s.ply --repeats 1 --warmup 0 --json", out) == 0);
  const nlohmann::json b = nlohmann::json::parse(out.substr(out.find('{')));
  CHECK(b["width"] == c0.width);
  CHECK(b["height"] == c0.height);
  CHECK(b["gaussians"] == cloud.size());
  CHECK(b["sh_degree"] == cloud.sh_degree);
  RenderState st0 = r.forward(params, c0, RenderSettings{});
  CHECK(b["intersections"] == st0.num_intersections());
}

TEST_CASE("render: a run's exposure path, its mid-exposure frame being the image eval scores", "[render][gpu]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("evflow_render_run");
  std::string out;
  expect_ok(dir, "simulate --scene gallery --out data --width 32 --height 24 --blur-px 3 --seed 4");
  const std::string small = " iterations=6 init_gaussians=300 max_gaussians=600 sh_degree=1 virtual_frames=2";
  expect_ok(dir, "train data --out blur method=blur-only" + small);
  expect_ok(dir, "eval blur --refine-iters 0");
  expect_ok(dir, "render blur --path exposure --out frames");
  size_t views = 0;
  for (auto& e : fs::directory_iterator(dir / "blur" / "eval" / "deblur")) {
    const std::string view = e.path().stem().string();
    for (int f = 0; f < 5; ++f) REQUIRE(fs::exists(dir / "frames" / (view + "_f00" + std::to_string(f) + ".png")));
    CHECK(!fs::exists(dir / "frames" / (view + "_f005.png")));
    CHECK(slurp(dir / "frames" / (view + "_f002.png")) == slurp(e.path()));  // mid-exposure: u = 0.5
    ++views;
  }
  REQUIRE(views > 0);
  // The first frame is the trajectory's start (u = 0): the same image from the checkpoint's knots
  // through a camera file.
  const io::Dataset data = io::load_dataset((dir / "data").string());
  const Checkpoint ck = read_checkpoint(dir / "blur" / "checkpoint.ckpt");
  ExposureTrajectory traj(data.train[1].camera, 0, 0.0);
  std::copy(ck.trajectories[1].knots.begin(), ck.trajectories[1].knots.end(), traj.data());
  {
    std::ofstream f(dir / "start.json");
    f << io::camera_to_json(traj.camera_at(0.0)).dump();
  }
  expect_ok(dir, "render blur --camera start.json --out start");
  CHECK(slurp(dir / "start" / "camera_000.png") == slurp(dir / "frames" / (data.train[1].name + "_f000.png")));
  CHECK(slurp(dir / "start" / "camera_000.png") != slurp(dir / "frames" / (data.train[1].name + "_f004.png")));
  // The views path renders the same mid-exposure image for a training view.
  expect_ok(dir, "render blur --path views --out views");
  for (auto& e : fs::directory_iterator(dir / "blur" / "eval" / "deblur"))
    CHECK(slurp(dir / "views" / ("train_" + e.path().filename().string())) == slurp(e.path()));
  // The orbit of a run starts at its first training view, upright: its first frame is that
  // view's recorded camera but for the roll, far closer to it than to it upside down.
  expect_ok(dir, "render blur --path orbit --frames 2 --width 32 --height 24 --out orbit");
  {
    std::ofstream f(dir / "first.json");
    f << io::camera_to_json(data.train[0].camera).dump();
  }
  expect_ok(dir, "render blur --camera first.json --out first");
  const io::Image a = io::read_image(dir / "orbit" / "orbit_000.png");
  const io::Image b = io::read_image(dir / "first" / "camera_000.png");
  double same = 0, flipped = 0;
  for (uint32_t y = 0; y < a.height; ++y)
    for (size_t k = 0; k < size_t(a.width) * a.channels; ++k) {
      const float va = a.data[y * a.width * a.channels + k];
      same += std::abs(va - b.data[y * b.width * b.channels + k]);
      flipped += std::abs(va - b.data[(b.height - 1 - y) * b.width * b.channels + k]);
    }
  INFO("orbit vs first view: " << same << ", vs it upside down: " << flipped);
  CHECK(same < 0.5 * flipped);
  // A plain run learned no trajectories.
  expect_ok(dir, "train data --out plain method=plain" + small);
  CHECK(run_evflow(dir, "render plain --path exposure --out x", out) != 0);
  CHECK(out.find("mode=plain") != std::string::npos);
  // The rasterizer benchmark on a run without a camera file: its first training view at
  // mid-exposure, the learned camera (the intersections of that very view).
  REQUIRE(run_evflow(dir, "bench raster --splats blur --repeats 1 --warmup 0 --json", out) == 0);
  const nlohmann::json bench = nlohmann::json::parse(out.substr(out.find('{')));
  CHECK(bench["width"] == 32);
  CHECK(bench["height"] == 24);
  CHECK(bench["gaussians"] == ck.cloud.size());
  ExposureTrajectory first(data.train[0].camera, 0, 0.0);
  std::copy(ck.trajectories[0].knots.begin(), ck.trajectories[0].knots.end(), first.data());
  auto& ctx = gpu_context();
  GaussianBuffers params(ctx, ck.cloud.size(), ck.cloud.sh_degree, "p_");
  params.upload(ck.cloud);
  Rasterizer r(ctx);
  CHECK(bench["intersections"] == r.forward(params, first.camera_at(0.5), RenderSettings{}).num_intersections());
  // Its dataset gone, the run names it and asks for a camera file.
  fs::rename(dir / "data", dir / "data_moved");
  CHECK(run_evflow(dir, "bench raster --splats blur --repeats 1 --warmup 0", out) != 0);
  CHECK(out.find("--camera") != std::string::npos);
  fs::rename(dir / "data_moved", dir / "data");
}
