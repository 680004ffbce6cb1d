// `evflow view` end to end under Xvfb: a window, a swapchain, 5 presented frames and a
// screenshot that must match the same camera rendered offscreen (docs/viewer.md).
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "../app/viewer/view_camera.h"
#include "cli_helpers.h"
#include "gpu_fixture.h"
#include "io/image.h"
#include "io/ply_splats.h"
#include "splat/rasterizer.h"
#include "splat/synthetic.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

// <build>/tests/evflow_tests -> <build>/evflow
using test::encode8;
using test::evflow_binary;
using test::on_path;
using test::quote;
using test::slurp;

// Runs `evflow view` on a synthetic PLY under Xvfb with a window of W x H (plus `extra`
// arguments), then compares its screenshot (expected size OW x OH) with the offscreen render of
// viewer::initial_view_camera at that size.
void view_and_compare(const std::string& tag, uint32_t W, uint32_t H, const std::string& extra, uint32_t OW,
                      uint32_t OH) {
  const fs::path bin = evflow_binary();
  INFO("looked for the evflow binary next to the tests folder: " << bin);
  REQUIRE(fs::exists(bin));
  if (!on_path("xvfb-run") || !on_path("Xvfb") || !on_path("xauth"))
    FAIL("the viewer test needs Xvfb: install the Debian packages xvfb and xauth (scripts/install-deps.sh)");

  const fs::path dir = fs::temp_directory_path() / ("evflow_viewer_test_" + std::to_string(::getpid()) + "_" + tag);
  fs::remove_all(dir);
  fs::create_directories(dir / "xdg");
  ::chmod((dir / "xdg").c_str(), 0700);

  // A small synthetic cloud in front of an identity camera.
  const Camera gen = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 1}, {0, -1, 0});
  const GaussianCloud cloud = synthetic_cloud(11, 3000, 1, gen);
  const fs::path ply = dir / "cloud.ply", png = dir / "shot.png", log = dir / "view.log";
  io::write_ply(ply, cloud);

  std::string cmd = "cd " + quote(dir.string()) + " && XDG_RUNTIME_DIR=" + quote((dir / "xdg").string()) +
                    " EVF_VALIDATION=1 timeout 300 xvfb-run -a -s '-screen 0 1024x768x24' " + quote(bin.string()) +
                    " view " + quote(ply.string()) + " --width " + std::to_string(W) + " --height " +
                    std::to_string(H) + " --frames 5 --fps-cap 0 --screenshot " + quote(png.string()) + " " + extra +
                    " > " + quote(log.string()) + " 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const int rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const std::string out = slurp(log);
  INFO("command: " << cmd);
  INFO("exit status " << rc << " after " << secs << " s (3 = validation messages); output:\n" << out);
  REQUIRE(rc == 0);
  REQUIRE(fs::exists(png));

  // The same camera rendered offscreen.
  const GaussianCloud loaded = io::read_ply(ply);
  const Camera cam = viewer::initial_view_camera(loaded, OW, OH);
  auto& ctx = test::gpu_context();
  GaussianBuffers params(ctx, loaded.size(), loaded.sh_degree, "vt_");
  params.upload(loaded);
  Rasterizer raster(ctx);
  RenderState raster_state(ctx);
  raster.forward(params, cam, RenderSettings{}, raster_state);
  const std::vector<float> ref = raster_state.outputs().rgb.read<float>(size_t(3) * OW * OH);
  test::require_no_validation_messages();

  const io::Image shot = io::read_image(png);
  REQUIRE(shot.width == OW);
  REQUIRE(shot.height == OH);
  size_t within = 0, lit = 0;
  int max_diff = 0;
  const size_t npx = size_t(OW) * OH;
  for (size_t i = 0; i < npx; ++i) {
    int worst = 0;
    bool any_lit = false;
    for (int c = 0; c < 3; ++c) {
      const int a = encode8(shot.data[i * 3 + c]);
      const int b = test::quantise8(ref[c * npx + i]);  // renders are sRGB
      worst = std::max(worst, std::abs(a - b));
      any_lit |= b > 8;
    }
    within += worst <= 1;
    lit += any_lit;
    max_diff = std::max(max_diff, worst);
  }
  const double frac = double(within) / double(npx), lit_frac = double(lit) / double(npx);
  INFO("pixels within 1 level: " << frac * 100 << "%, max difference " << max_diff << " levels, lit pixels "
                                 << lit_frac * 100 << "%");
  WARN("viewer " << tag << ": " << OW << "x" << OH << " screenshot vs offscreen: " << frac * 100
                 << "% of pixels within 1 level, max difference " << max_diff << " levels; " << lit_frac * 100
                 << "% lit; viewer run " << secs << " s");
  CHECK(lit_frac > 0.2);  // the view actually shows the cloud
  CHECK(frac >= 0.999);
  fs::remove_all(dir);
}

}  // namespace

TEST_CASE("evflow view under Xvfb presents frames and its screenshot matches the offscreen render", "[viewer]") {
  view_and_compare("plain", 320, 240, "", 320, 240);
}

TEST_CASE("evflow view rebuilds its swapchain on a resize and renders at the new size", "[viewer]") {
  view_and_compare("resize", 320, 240, "--resize-to 256x200", 256, 200);
}

TEST_CASE("viewer orbit: a training view's pose in a world whose up is +y, and its whole width in a tall window",
          "[viewer]") {
  using viewer::Orbit;
  // Level cameras of a world whose up is +y (glTF's): image down is world -y.
  const std::array<double, 3> up{0, 1, 0};
  std::vector<Camera> level;
  for (double x : {-1.0, 0.0, 1.0}) level.push_back(Camera::look_at(160, 120, 50, {0, 0, -4}, {x, 0, 0}, up));
  const std::array<double, 9> basis = viewer::basis_from_cameras(level);
  // A training camera looking down and to the side, without roll about world up.
  const Camera cam = Camera::look_at(160, 120, 50, {1, 0.5, -4}, {0.2, -0.3, 0}, up);
  const Orbit o = viewer::orbit_from_camera(cam, 3.0, basis);
  const Camera back = viewer::orbit_camera(o, cam.width, cam.height);
  for (int i = 0; i < 9; ++i) CHECK(std::abs(back.R[i] - cam.R[i]) < 1e-9);
  const auto c0 = cam.center(), c1 = back.center();
  for (int k = 0; k < 3; ++k) CHECK(std::abs(c0[k] - c1[k]) < 1e-9);
  CHECK(std::abs(back.fy - cam.fy) < 1e-9);
  // Without the cameras' frame the orbit keeps OpenCV's up (-y): the image comes out upside down.
  const Camera opencv = viewer::orbit_camera(viewer::orbit_from_camera(cam, 3.0), cam.width, cam.height);
  CHECK(opencv.R[4] * cam.R[4] < 0);
  // In a window half as wide the horizontal field of view stays the camera's.
  const Camera tall = viewer::orbit_camera(o, cam.width / 2, cam.height);
  CHECK(std::abs(0.5 * tall.width / tall.fx - 0.5 * cam.width / cam.fx) < 1e-9);
  CHECK(tall.fy < cam.fy);
}
