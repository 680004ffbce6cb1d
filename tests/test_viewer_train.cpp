// `evflow train --view` (docs/viewer.md): the viewer's drawing kernels offscreen, and the live
// training viewer end to end under Xvfb: its panels against the dataset, offscreen renders and
// the trainer's snapshot (flow, warped events, LDI frames, residuals), the pause / single-step /
// view / panel keys and the UI's widgets through --view-script.
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "events/warped_events.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "io/dataset_writer.h"
#include "io/image.h"
#include "metrics/srgb_metrics.h"
#include "prior/residual_prior.h"
#include "sim/flow_truth.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"
#include "train/training_data.h"
#include "viewer/canvas.h"
#include "viewer/event_image.h"
#include "viewer/flow_image.h"
#include "viewer/layout.h"
#include "viewer/residual_image.h"

using namespace evflow;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using test::encode8;
using test::evflow_binary;
using test::on_path;
using test::quote;
using test::slurp;

// A fresh folder with a 0700 XDG_RUNTIME_DIR inside.
fs::path fresh_dir(const std::string& tag) {
  const fs::path dir = fs::temp_directory_path() / ("evflow_trainview_test_" + std::to_string(::getpid()) + "_" + tag);
  fs::remove_all(dir);
  fs::create_directories(dir / "xdg");
  ::chmod((dir / "xdg").c_str(), 0700);
  return dir;
}

// 3 training views of 96 x 72 (+1 novel) with exposure windows and a few events: view 0's
// exposure holds 3 positive events at (10, 10) and 3 negative ones at (40, 30); one more event
// at (60, 50) lies in view 1's exposure only. Written as float EXR so that it loads back exactly.
fs::path write_dataset(const fs::path& dir) {
  auto& ctx = test::gpu_context();
  io::Dataset d = render_synthetic_dataset(ctx, 96, 72, 3, 1, 800, 7);
  d.layout = "evflow";
  for (size_t v = 0; v < d.train.size(); ++v) {
    d.train[v].exposure_start = 0.1 * double(v);
    d.train[v].exposure_end = 0.1 * double(v) + 0.04;
  }
  d.events.width = 96;
  d.events.height = 72;
  for (int k = 0; k < 3; ++k) {
    d.events.push(10, 10, 0.001 + 0.005 * k, +1);
    d.events.push(40, 30, 0.003 + 0.005 * k, -1);
  }
  d.events.push(60, 50, 0.12, +1);
  const fs::path data = dir / "data";
  io::WriteOptions wo;
  wo.image_ext = ".exr";
  io::write_evflow_dataset(d, data, wo);
  return data;
}

struct Run {
  int rc = -1;
  std::string out;
  double secs = 0;
};

Run run_evflow(const fs::path& dir, const std::string& args, bool xvfb = true) {
  const fs::path log = dir / "run.log";
  std::string cmd = "cd " + quote(dir.string()) + " && XDG_RUNTIME_DIR=" + quote((dir / "xdg").string()) +
                    " EVF_VALIDATION=1 timeout 300 " + (xvfb ? "xvfb-run -a -s '-screen 0 1024x768x24' " : "") +
                    quote(evflow_binary().string()) + " " + args + " > " + quote(log.string()) + " 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  Run r;
  r.secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = "command: " + cmd + "\n" + slurp(log);
  return r;
}

void require_xvfb() {
  REQUIRE(fs::exists(evflow_binary()));
  if (!on_path("xvfb-run") || !on_path("Xvfb") || !on_path("xauth"))
    FAIL("the viewer tests need Xvfb: install the Debian packages xvfb and xauth (scripts/install-deps.sh)");
}

// The training configuration both the CLI run and the in-process reference use. (From its
// near-constant start, one blur-only step moves every knot of a trajectory alike, so renders at
// different u stay equal to 8 bits after it: the panels' checks compare the render path, not
// which u a tile shows; the u values are checked from the report.)
const std::vector<std::pair<std::string, std::string>> kKeys = {
    {"iterations", "3"},     {"init_gaussians", "400"}, {"sh_degree", "0"}, {"mode", "blur"},
    {"virtual_frames", "1"}, {"densify", "false"},      {"seed", "3"},      {"lr_trajectory_init", "0.05"}};

std::string key_args() {
  std::string s;
  for (auto& [k, v] : kKeys) s += " " + k + "=" + v;
  return s;
}

// Compares a screenshot rectangle with a planar linear RGB image resampled the viewer's way.
// Returns the fraction of pixels whose 8-bit values are within one level on every channel.
// planar: sRGB values (what the canvas shows: renders as they are, other images encoded).
double tile_match(const io::Image& shot, const json& tile, const std::vector<float>& planar, int* max_diff) {
  const uint32_t x0 = tile["x"], y0 = tile["y"], w = tile["w"], h = tile["h"], sw = tile["src_w"], sh = tile["src_h"];
  REQUIRE(planar.size() == size_t(3) * sw * sh);
  REQUIRE(x0 + w <= shot.width);
  REQUIRE(y0 + h <= shot.height);
  size_t within = 0;
  *max_diff = 0;
  const size_t n = size_t(sw) * sh;
  for (uint32_t dy = 0; dy < h; ++dy)
    for (uint32_t dx = 0; dx < w; ++dx) {
      const size_t s = size_t(viewer::nearest_source(dy, h, sh)) * sw + viewer::nearest_source(dx, w, sw);
      const size_t p = (size_t(y0 + dy) * shot.width + x0 + dx) * 3;
      int worst = 0;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, std::abs(int(encode8(shot.data[p + c])) - int(test::quantise8(planar[c * n + s]))));
      within += worst <= 1;
      *max_diff = std::max(*max_diff, worst);
    }
  return double(within) / double(size_t(w) * h);
}

const json& panel(const json& report, const std::string& id) {
  for (const auto& p : report["panels"])
    if (p["id"] == id) return p;
  FAIL("no panel '" << id << "' in the report");
  static json none;
  return none;
}

std::array<int, 3> shot_px(const io::Image& shot, uint32_t x, uint32_t y) {
  const size_t p = (size_t(y) * shot.width + x) * 3;
  return {encode8(shot.data[p]), encode8(shot.data[p + 1]), encode8(shot.data[p + 2])};
}

// A blur-mode run of `iterations` steps with the viewer open for 9 frames (budget 0.5, no frame
// cap) and `script`; requires it to finish and returns its viewer report.
json run_scripted(const fs::path& dir, const fs::path& data_dir, const fs::path& run, int iterations, int width,
                  int height, const std::string& script) {
  const fs::path report_json = dir / "report.json";
  const Run r = run_evflow(dir, "train " + quote(data_dir.string()) + " --out " + quote(run.string()) +
                                    " iterations=" + std::to_string(iterations) +
                                    " init_gaussians=300 sh_degree=0 mode=blur virtual_frames=1 densify=false"
                                    " --view --view-width " +
                                    std::to_string(width) + " --view-height " + std::to_string(height) +
                                    " --view-frames 9 --view-budget 0.5 --view-fps-cap 0 --view-script " + script +
                                    " --view-report " + quote(report_json.string()));
  INFO(r.out);
  REQUIRE(r.rc == 0);
  REQUIRE(r.out.find("done: " + std::to_string(iterations) + " steps") != std::string::npos);
  const json rep = json::parse(slurp(report_json));
  REQUIRE(rep["frames"].size() == 9);
  return rep;
}

// The report's frame log, by frame number (from 1).
struct FrameLog {
  const json& frames;
  uint32_t step(int frame) const { return frames[frame - 1]["step"].get<uint32_t>(); }
  bool paused(int frame) const { return frames[frame - 1]["paused"].get<bool>(); }
};

}  // namespace

TEST_CASE("viewer canvas: fill and nearest-neighbour blit match their host definitions", "[viewer]") {
  auto& ctx = test::gpu_context();
  gpu::Commands cmd(ctx);
  viewer::Canvas canvas(ctx, cmd);
  const uint32_t W = 160, H = 48;
  canvas.resize(W, H, true);  // B,G,R,A byte order
  // A 7 x 5 gradient image blitted into a 20 x 13 rectangle.
  const uint32_t sw = 7, sh = 5;
  std::vector<float> img(3 * sw * sh);
  for (size_t i = 0; i < img.size(); ++i) img[i] = float(i % 11) / 10.f;
  gpu::Buffer src(ctx, img.size() * 4, "vt_src");
  src.write(img);
  const viewer::Rect r{3, 20, 20, 13};
  canvas.fill({0, 0, W, H}, viewer::rgba(10, 20, 30));
  canvas.blit(src, sw, sh, r);
  cmd.submit();
  const std::vector<uint32_t> px = canvas.packed().read<uint32_t>(size_t(W) * H);
  test::require_no_validation_messages();

  auto bgra = [](uint32_t r8, uint32_t g8, uint32_t b8) { return b8 | (g8 << 8) | (r8 << 16) | (255u << 24); };
  size_t bad = 0, inside = 0;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      uint32_t want = bgra(10, 20, 30);
      if (x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h) {
        const size_t s =
            size_t(viewer::nearest_source(y - r.y, r.h, sh)) * sw + viewer::nearest_source(x - r.x, r.w, sw);
        const size_t n = size_t(sw) * sh;
        want = bgra(test::quantise8(img[s]), test::quantise8(img[n + s]), test::quantise8(img[2 * n + s]));
        ++inside;
      }
      bad += px[size_t(y) * W + x] != want;
    }
  INFO("pixels differing from the host reference: " << bad);
  CHECK(bad == 0);
  CHECK(inside == size_t(r.w) * r.h);
}

TEST_CASE("viewer layout: nearest-neighbour source index, aspect fit and tile grids", "[viewer]") {
  // The mapping covers the source evenly and stays in range.
  for (uint32_t dst : {1u, 7u, 64u, 333u})
    for (uint32_t src : {1u, 5u, 64u, 346u}) {
      uint32_t prev = 0;
      for (uint32_t d = 0; d < dst; ++d) {
        const uint32_t s = viewer::nearest_source(d, dst, src);
        REQUIRE(s < src);
        REQUIRE(s >= prev);
        prev = s;
      }
      if (dst == src)
        for (uint32_t d = 0; d < dst; ++d) REQUIRE(viewer::nearest_source(d, dst, src) == d);
    }
  const viewer::Rect f = viewer::fit_aspect({10, 20, 300, 100}, 4, 3);
  CHECK(f.h == 100);
  CHECK(f.w == 133);
  CHECK(f.x == 10 + (300 - 133) / 2);
  const auto tiles = viewer::tile_grid({0, 0, 400, 300}, 7, 4, 3);
  REQUIRE(tiles.size() == 7);
  for (size_t i = 0; i < tiles.size(); ++i)
    for (size_t j = i + 1; j < tiles.size(); ++j) {
      const bool apart = tiles[i].x + tiles[i].w <= tiles[j].x || tiles[j].x + tiles[j].w <= tiles[i].x ||
                         tiles[i].y + tiles[i].h <= tiles[j].y || tiles[j].y + tiles[j].h <= tiles[i].y;
      REQUIRE(apart);
    }
  // Six tiles in a 300 x 150 box: three to a row at best, which splits tiles 2 and 3 over two
  // rows; in groups of two, four to a row, each pair on one row.
  const auto free6 = viewer::tile_grid({0, 0, 300, 150}, 6, 4, 3);
  const auto pairs6 = viewer::tile_grid({0, 0, 300, 150}, 6, 4, 3, 2, 2);
  REQUIRE(free6.size() == 6);
  REQUIRE(pairs6.size() == 6);
  CHECK(free6[2].y == free6[0].y);
  CHECK(free6[3].y > free6[2].y);
  for (size_t k = 0; k < 6; k += 2) CHECK(pairs6[k + 1].y == pairs6[k].y);
  CHECK(pairs6[3].y == pairs6[0].y);
  CHECK(pairs6[4].y > pairs6[0].y);
  const auto l = viewer::train_layout(1280, 720, 4, 20);
  CHECK(l.main.w == 640);
  REQUIRE(l.boxes.size() == 4);
  CHECK(l.boxes[3].x + l.boxes[3].w <= 1280);
  CHECK(viewer::train_layout(800, 600, 0, 20).main.w == 800);
}

TEST_CASE("train --view: bad viewer options give clear errors before a window opens", "[viewer]") {
  REQUIRE(fs::exists(evflow_binary()));
  const fs::path dir = fresh_dir("badargs");
  const fs::path data = write_dataset(dir);
  struct Case {
    std::string args, message;
  } cases[] = {
      {"--view-frames 3", "--view-frames needs --view"},
      {"--view --view-index 7", "--view-index 7: the dataset has 3 training views"},
      {"--view --view-script 2:zz", "unknown key 'zz'"},
      {"--view --view-script x:n", "is not FRAME:KEY"},
      {"--view --view-script 2:slide=u@1.5", "is not FRAME:slide=WIDGET@FRACTION"},
      {"--view --view-script 2:slide=u", "is not FRAME:slide=WIDGET@FRACTION"},
      {"--view --view-script 2:click=", "names no widget"},
      {"--view --view-budget 0", "--view-budget must be in (0, 1]"},
  };
  for (const auto& c : cases) {
    const Run r = run_evflow(
        dir, "train " + quote(data.string()) + " --out " + quote((dir / "run").string()) + " " + c.args, false);
    INFO(r.out);
    CHECK(r.rc == 1);
    CHECK(r.out.find(c.message) != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("train --view under Xvfb: panels show the blurry input, the renders and the events of the view", "[viewer]") {
  require_xvfb();
  const fs::path dir = fresh_dir("panels");
  const fs::path data_dir = write_dataset(dir);
  const fs::path shot_png = dir / "shot.png", report_json = dir / "report.json";
  // Paused from the start; one single step before frame 2; the u slider pressed at a quarter of
  // its range in frame 3; 3 frames, then training finishes.
  const Run r =
      run_evflow(dir, "train " + quote(data_dir.string()) + " --out " + quote((dir / "run").string()) + key_args() +
                          " --view --view-width 640 --view-height 400 --view-paused --view-frames 3"
                          " --view-script 2:n,3:slide=u@0.25 --view-fps-cap 0 --view-screenshot " +
                          quote(shot_png.string()) + " --view-report " + quote(report_json.string()));
  INFO(r.out);
  REQUIRE(r.rc == 0);
  REQUIRE(r.out.find("done: 3 steps") != std::string::npos);
  const json rep = json::parse(slurp(report_json));
  INFO(rep.dump(1));
  // Frame log: step 0, then exactly one step after N, still paused.
  REQUIRE(rep["frames"].size() == 3);
  CHECK(rep["frames"][0]["step"] == 0);
  CHECK(rep["frames"][1]["step"] == 1);
  CHECK(rep["frames"][2]["step"] == 1);
  for (const auto& f : rep["frames"]) CHECK(f["paused"] == true);
  REQUIRE(rep["content"]["step"] == 1);
  REQUIRE(rep["content"]["view"] == 0);
  const io::Image shot = io::read_image(shot_png);
  REQUIRE(shot.width == rep["canvas"][0].get<uint32_t>());

  // The same run in this process: one step, then the renders the panels show.
  auto& ctx = test::gpu_context();
  const io::Dataset data = io::load_dataset(data_dir);
  TrainConfig cfg;
  for (auto& [k, v] : kKeys) cfg.set(k, v);
  Trainer t(ctx, data, cfg);
  t.step();
  const ExposureTrajectory& traj = t.trajectories().at(0);
  int max_diff = 0;

  // Blurry input.
  const json& blurry = panel(rep, "blurry")["tiles"][0];
  std::vector<float> blurry_srgb = io::planar_rgb(data.train[0].blurry);
  for (float& x : blurry_srgb) x = io::linear_to_srgb(x);
  double m = tile_match(shot, blurry, blurry_srgb, &max_diff);
  WARN("blurry panel " << blurry["w"] << "x" << blurry["h"] << ": " << m * 100 << "% within 1 level, max " << max_diff);
  CHECK(m >= 0.999);

  // The render panel at the u the slider set (frames 1-2 at 0.5, frame 3 near 0.25) =
  // Trainer::render of trajectories()[0].camera_at(u).
  CHECK(rep["frames"][1]["u"] == 0.5);
  const double u = rep["frames"][2]["u"];
  CHECK(std::abs(u - 0.25) < 0.01);
  const std::vector<float> at_u = t.render(traj.camera_at(u));
  m = tile_match(shot, panel(rep, "mid")["tiles"][0], at_u, &max_diff);
  WARN("render panel at u = " << u << ": " << m * 100 << "% within 1 level, max " << max_diff);
  CHECK(m >= 0.99);
  // (After one step the trajectory has barely moved: renders at u = 0.25 and 0.5 are equal to
  // 8 bits here, so this compares the render path, not which u it used; the u value is checked
  // above and by the label.)
  const std::vector<float> mid = t.render(traj.camera_at(0.5));

  // Virtual frames at u = 0, 0.5, 1 (virtual_frames = 1), and the PSNR of their mean.
  const auto& vt = panel(rep, "virtual")["tiles"];
  REQUIRE(vt.size() == 3);
  const std::vector<double> us = ExposureTrajectory::virtual_times(1);
  std::vector<float> mean(mid.size(), 0.f);
  for (size_t i = 0; i < us.size(); ++i) {
    const std::vector<float> img = t.render(traj.camera_at(us[i]));
    for (size_t k = 0; k < img.size(); ++k) mean[k] += io::srgb_to_linear(img[k]) / 3.f;  // blur in linear light
    m = tile_match(shot, vt[i], img, &max_diff);
    CHECK(m >= 0.99);
  }
  const std::vector<float> target = io::planar_rgb(data.train[0].blurry);
  // The overlay scores as `evflow eval` does: 8-bit sRGB.
  const uint32_t nv = uint32_t(mean.size());
  const double psnr = metrics::psnr(metrics::encode_linear(mean, nv, 1, 1), metrics::encode_linear(target, nv, 1, 1));
  CHECK(std::abs(rep["content"]["psnr"].get<double>() - psnr) < 0.01);

  // Events: 3 positive at (10, 10) -> red, 3 negative at (40, 30) -> blue, else grey; the
  // event of view 1's exposure does not show.
  CHECK(rep["content"]["events_pos"] == 3);
  CHECK(rep["content"]["events_neg"] == 3);
  const json& ev = panel(rep, "events")["tiles"][0];
  const viewer::EventImage ei = viewer::event_image(data, 0);
  m = tile_match(shot, ev, ei.rgb, &max_diff);
  CHECK(m >= 0.999);
  size_t red = 0, blue = 0, grey = 0, other = 0;
  const uint32_t x0 = ev["x"], y0 = ev["y"], w = ev["w"], h = ev["h"];
  for (uint32_t dy = 0; dy < h; ++dy)
    for (uint32_t dx = 0; dx < w; ++dx) {
      const uint32_t sx = viewer::nearest_source(dx, w, 96), sy = viewer::nearest_source(dy, h, 72);
      const auto p = shot_px(shot, x0 + dx, y0 + dy);
      const bool is_red = p == std::array<int, 3>{255, 0, 0}, is_blue = p == std::array<int, 3>{0, 0, 255};
      const bool is_grey = p == std::array<int, 3>{128, 128, 128};
      if (sx == 10 && sy == 10)
        red += is_red, other += !is_red;
      else if (sx == 40 && sy == 30)
        blue += is_blue, other += !is_blue;
      else
        grey += is_grey, other += !is_grey;
    }
  INFO("events panel: red " << red << ", blue " << blue << ", grey " << grey << ", other " << other);
  CHECK(red > 0);
  CHECK(blue > 0);
  CHECK(other == 0);
  // The UI window lies over the free-camera view, not over the panels, and drew text in the
  // screenshot (pure white glyph pixels; the window's background is translucent dark grey).
  const json& win = rep["widgets"]["window"];
  const json& main = rep["main"];
  REQUIRE(win["x"].get<double>() >= main["x"].get<double>());
  REQUIRE(win["x"].get<double>() + win["w"].get<double>() <= main["x"].get<double>() + main["w"].get<double>());
  size_t white = 0;
  for (uint32_t y = uint32_t(win["y"].get<double>()); y < uint32_t(win["y"].get<double>() + win["h"].get<double>());
       ++y)
    for (uint32_t x = uint32_t(win["x"].get<double>()); x < uint32_t(win["x"].get<double>() + win["w"].get<double>());
         ++x)
      white += shot_px(shot, x, y) == std::array<int, 3>{255, 255, 255};
  CHECK(white > 200);
  test::require_no_validation_messages();
  fs::remove_all(dir);
}

TEST_CASE("train --view under Xvfb: pause stops training, N steps exactly once, views and panels switch", "[viewer]") {
  require_xvfb();
  const fs::path dir = fresh_dir("keys");
  const fs::path data_dir = write_dataset(dir);
  // Running at first; Space before frame 3 pauses, Right before 4 shows view 1, N before 5 and
  // 6 steps once each, 3 before 7 hides the virtual frames, Space before 8 resumes.
  const json rep = run_scripted(dir, data_dir, dir / "run", 40, 480, 300, "3:space,4:right,5:n,6:n,7:3,8:space");
  INFO(rep["frames"].dump(1));
  const FrameLog log{rep["frames"]};
  auto step = [&](int frame) { return log.step(frame); };
  auto paused = [&](int frame) { return log.paused(frame); };
  const auto& f = rep["frames"];
  CHECK(step(1) == 0);
  CHECK_FALSE(paused(2));
  CHECK(step(2) >= 1);  // training ran between frames 1 and 2
  for (int k = 3; k <= 7; ++k) CHECK(paused(k));
  CHECK(step(3) == step(2));  // paused: no step
  CHECK(step(4) == step(3));
  CHECK(step(5) == step(4) + 1);  // N: exactly one step
  CHECK(step(6) == step(5) + 1);
  CHECK(step(7) == step(6));
  CHECK_FALSE(paused(8));
  CHECK(step(9) > step(8));  // resumed: training ran between frames 8 and 9
  CHECK(f[2]["view"] == 0);
  CHECK(f[3]["view"] == 1);
  CHECK(f[3]["content_step"] == step(4));  // the panels re-rendered for the new view
  std::vector<std::string> ids;
  for (const auto& p : rep["panels"]) ids.push_back(p["id"]);
  CHECK(ids == std::vector<std::string>{"blurry", "mid", "events"});
  CHECK(rep["content"]["view"] == 1);
  CHECK(rep["content"]["events_pos"] == 1);
  CHECK(rep["content"]["events_neg"] == 0);
  fs::remove_all(dir);
}

TEST_CASE("train --view under Xvfb: the UI's buttons, sliders and check boxes drive training and the panels",
          "[viewer]") {
  require_xvfb();
  const fs::path dir = fresh_dir("widgets");
  const fs::path data_dir = write_dataset(dir);
  const fs::path run = dir / "run";
  // Running at first. Frame 2: Pause; 3: Step; 4: the view slider to its right end (view 2);
  // 5: the panel check box "events" off; 6: the l1_ssim weight slider to 0; 7: Screenshot;
  // 8: Resume. Widget actions press the mouse through ImGui when their frame is drawn.
  const json rep = run_scripted(dir, data_dir, run, 60, 800, 560,
                                "2:click=pause,3:click=step,4:slide=view@1,5:click=panel.events,"
                                "6:slide=weight.l1_ssim@0,7:click=screenshot,8:click=pause");
  INFO(rep["frames"].dump(1));
  const FrameLog log{rep["frames"]};
  auto step = [&](int frame) { return log.step(frame); };
  auto paused = [&](int frame) { return log.paused(frame); };
  const auto& f = rep["frames"];
  CHECK_FALSE(paused(1));
  for (int k = 2; k <= 7; ++k) CHECK(paused(k));  // Pause clicked in frame 2
  CHECK(step(3) == step(2));
  CHECK(step(4) == step(3) + 1);  // Step clicked in frame 3: exactly one step before frame 4
  for (int k = 5; k <= 7; ++k) CHECK(step(k) == step(4));
  CHECK_FALSE(paused(8));  // Resume clicked in frame 8
  CHECK(f[2]["view"] == 0);
  CHECK(f[3]["view"] == 2);  // the view slider's right end
  std::vector<std::string> ids;
  for (const auto& p : rep["panels"]) ids.push_back(p["id"]);
  CHECK(ids == std::vector<std::string>{"blurry", "mid", "virtual"});
  // A run without the LDI branch or the residual loss has neither panel, nor their check boxes.
  CHECK_FALSE(rep["widgets"].contains("panel.ldi"));
  CHECK_FALSE(rep["widgets"].contains("panel.residual"));
  CHECK(rep["widgets"].contains("panel.warped"));
  // The weight slider set the trainer's weight: every step after it has a total loss of 0, every
  // step before it a positive one.
  CHECK(rep["weights"]["l1_ssim"] == 0.0);
  const uint32_t zeroed_at = step(6);
  std::ifstream curve(run / "curve.csv");
  std::string line;
  std::getline(curve, line);
  REQUIRE(line.rfind("step,view,loss,", 0) == 0);
  size_t before = 0, after = 0;
  while (std::getline(curve, line)) {
    std::stringstream ss(line);
    std::string s_step, s_view, s_loss;
    std::getline(ss, s_step, ',');
    std::getline(ss, s_view, ',');
    std::getline(ss, s_loss, ',');
    const double loss = std::stod(s_loss);
    if (uint32_t(std::stoul(s_step)) <= zeroed_at) {
      CHECK(loss > 0);
      ++before;
    } else {
      CHECK(loss == 0);
      ++after;
    }
  }
  CHECK(before >= 1);
  CHECK(after >= 1);
  // The screenshot button wrote the frame with the UI into the run folder, without temporaries.
  CHECK(rep["screenshots"] == 1);
  const fs::path shot = rep["last_screenshot"].get<std::string>();
  REQUIRE(fs::exists(shot));
  CHECK(shot.parent_path() == run);
  const io::Image im = io::read_image(shot);
  CHECK(im.width == rep["canvas"][0].get<uint32_t>());
  CHECK(im.height == rep["canvas"][1].get<uint32_t>());
  for (const auto& e : fs::directory_iterator(run))
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
  fs::remove_all(dir);
}

namespace {

// Hue in degrees [0, 360) of an 8-bit RGB colour (-1 for greys).
double hue_deg(const std::array<int, 3>& p) {
  const int mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
  if (mx - mn < 8) return -1;
  const double d = mx - mn;
  double h = mx == p[0]   ? std::fmod((p[1] - p[2]) / d + 6.0, 6.0)
             : mx == p[1] ? (p[2] - p[0]) / d + 2.0
                          : (p[0] - p[1]) / d + 4.0;
  return 60.0 * h;
}

// A flow=gt run of the simulated folder `sim` (paused at step 0, 3 frames): returns its report.
json run_flow_view(const fs::path& dir, const std::string& script, const fs::path& shot) {
  const fs::path report_json = dir / "report.json";
  const Run r = run_evflow(dir,
                           "train sim --out run method=blur+events+warp flow=gt event_from=0 iterations=1"
                           " init_gaussians=400 sh_degree=0 virtual_frames=2 densify=false seed=3"
                           " --view --view-width 720 --view-height 480 --view-paused --view-frames 3"
                           " --view-fps-cap 0 --view-script " +
                               script + " --view-screenshot " + quote(shot.string()) + " --view-report " +
                               quote(report_json.string()));
  INFO(r.out);
  REQUIRE(r.rc == 0);
  return json::parse(slurp(report_json));
}

bool has_panel(const json& rep, const std::string& id) {
  for (const auto& p : rep["panels"])
    if (p["id"] == id) return true;
  return false;
}

// The fraction of a tile's pixels that differ by more than 8 levels between two screenshots.
double changed(const io::Image& a, const io::Image& b, const json& tile) {
  size_t n = 0, diff = 0;
  for (uint32_t y = tile["y"]; y < tile["y"].get<uint32_t>() + tile["h"].get<uint32_t>(); ++y)
    for (uint32_t x = tile["x"]; x < tile["x"].get<uint32_t>() + tile["w"].get<uint32_t>(); ++x) {
      const auto p = shot_px(a, x, y), q = shot_px(b, x, y);
      int worst = 0;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(p[c] - q[c]));
      diff += worst > 8, ++n;
    }
  return double(diff) / double(std::max<size_t>(n, 1));
}

}  // namespace

TEST_CASE("train --view under Xvfb: the flow and warped-event panels show the interval's flow, M_i and P_i",
          "[viewer]") {
  require_xvfb();
  const fs::path dir = fresh_dir("flow");
  {
    const Run r = run_evflow(dir,
                             "simulate --scene gallery --out sim --width 64 --height 48 --blur-px 8 --seed 3 "
                             "--train-views 2 --novel-views 1",
                             false);
    INFO(r.out);
    REQUIRE(r.rc == 0);
  }
  // The interval slider pressed at its right end in frame 2: interval 3 of 4.
  const fs::path shot_png = dir / "shot.png";
  const json rep = run_flow_view(dir, "2:slide=interval@1", shot_png);
  INFO(rep["content"].dump(1));
  const json& fl = rep["content"]["flow"];
  REQUIRE(fl["shown"] == true);
  REQUIRE(fl["warped"] == true);
  CHECK(fl["intervals"] == 4);
  REQUIRE(fl["interval"] == 3);
  const io::Image shot = io::read_image(shot_png);

  // The trainer's snapshot of the same interval, in this process, pictured the viewer's way.
  auto& ctx = test::gpu_context();
  const io::Dataset data = io::load_dataset(dir / "sim");
  TrainConfig cfg;
  for (const char* kv : {"method=blur+events+warp", "flow=gt", "event_from=0", "iterations=1", "init_gaussians=400",
                         "sh_degree=0", "virtual_frames=2", "densify=false", "seed=3"}) {
    const std::string s = kv;
    cfg.set(s.substr(0, s.find('=')), s.substr(s.find('=') + 1));
  }
  Trainer t(ctx, data, cfg);
  const ViewSnapshot snap = t.snapshot(0, 3);
  REQUIRE(snap.has_flow);
  REQUIRE(snap.flow.warped);
  const viewer::FlowImages im = viewer::flow_images(snap.flow);
  int max_diff = 0;
  const json& flow_tile = panel(rep, "flow")["tiles"][0];
  CHECK(tile_match(shot, flow_tile, im.flow, &max_diff) >= 0.99);
  const json& warped = panel(rep, "warped")["tiles"];
  REQUIRE(warped.size() == 2);
  CHECK(tile_match(shot, warped[0], im.measured, &max_diff) >= 0.99);
  CHECK(tile_match(shot, warped[1], im.predicted, &max_diff) >= 0.99);

  // The panel's hue is the ground-truth flow's direction + 180 degrees wherever the flow is long
  // enough to be saturated (the simulator's flow, read independently of the trainer).
  const auto truth = sim::ground_truth_interval_flow(dir / "sim", data.train[0].name, snap.times);
  REQUIRE(truth);
  const std::vector<float>& d = (*truth)[3];
  const uint32_t W = 64, H = 48, x0 = flow_tile["x"], y0 = flow_tile["y"], w = flow_tile["w"], h = flow_tile["h"];
  size_t tested = 0, agree = 0;
  for (uint32_t dy = 0; dy < h; ++dy)
    for (uint32_t dx = 0; dx < w; ++dx) {
      const size_t p = size_t(viewer::nearest_source(dy, h, H)) * W + viewer::nearest_source(dx, w, W);
      if (!(std::hypot(d[2 * p], d[2 * p + 1]) > 0.5 * fl["max_px"].get<double>())) continue;
      const double want = std::atan2(d[2 * p + 1], d[2 * p]) * 180.0 / M_PI + 180.0;
      const double got = hue_deg(shot_px(shot, x0 + dx, y0 + dy));
      const double off = std::fabs(std::remainder(got - want, 360.0));
      ++tested, agree += got >= 0 && off < 15.0;
    }
  WARN("flow panel: " << agree << " of " << tested << " saturated pixels with the gt direction's hue");
  CHECK(tested > 500);
  CHECK(agree >= 0.95 * double(tested));
  // What the trainer gave is what L_ev^w compares, recomputed here independently on the interior:
  // M_3 = the events of [t_3, t_4) warped along the ground-truth flow to t_4; P_3 = -(grad L_4 . d_3)
  // of frame 4's render (log luminance of linear light, central differences).
  const io::View& v0 = data.train[0];
  const double t3 = v0.exposure_start + 0.75 * (v0.exposure_end - v0.exposure_start);
  const auto [theta_pos, theta_neg] = event_thresholds(data, t.config());
  const std::vector<float> m_host = warp_events_to_end(data.events, t3, v0.exposure_end, d, theta_pos, theta_neg);
  std::vector<float> frame4 = snap.frames[4]->read<float>(size_t(3) * W * H);
  for (float& x : frame4) x = io::srgb_to_linear(x);
  auto log_luma = [&](size_t q) {
    return std::log(1e-3 +
                    std::max(0.0, 0.2126 * frame4[q] + 0.7152 * frame4[W * H + q] + 0.0722 * frame4[2 * W * H + q]));
  };
  double m_max = 0, p_max = 0, m_err = 0, p_err = 0;
  for (uint32_t y = 1; y + 1 < H; ++y)
    for (uint32_t x = 1; x + 1 < W; ++x) {
      const size_t q = size_t(y) * W + x;
      const double dx = std::isfinite(d[2 * q]) ? d[2 * q] : 0.0, dy = std::isfinite(d[2 * q + 1]) ? d[2 * q + 1] : 0.0;
      const double p_host =
          -(0.5 * (log_luma(q + 1) - log_luma(q - 1)) * dx + 0.5 * (log_luma(q + W) - log_luma(q - W)) * dy);
      m_max = std::max(m_max, std::fabs(double(m_host[q]))), p_max = std::max(p_max, std::fabs(p_host));
      m_err = std::max(m_err, std::fabs(double(snap.flow.measured[q]) - m_host[q]));
      p_err = std::max(p_err, std::fabs(double(snap.flow.predicted[q]) - p_host));
    }
  WARN("M_3: largest difference " << m_err << " of " << m_max << "; P_3: " << p_err << " of " << p_max);
  CHECK(m_err <= 1e-4 * m_max);
  CHECK(p_err <= 1e-3 * p_max);
  // M_i and P_i carry both signs (the scene moves: edges brighten and darken).
  for (const auto* v : {&snap.flow.measured, &snap.flow.predicted}) {
    CHECK(*std::max_element(v->begin(), v->end()) > 0);
    CHECK(*std::min_element(v->begin(), v->end()) < 0);
  }

  // Toggled off (key 5 before frame 1, the "warped" check box in frame 2): both leave the
  // window, and what was drawn where they were changes.
  const fs::path off_png = dir / "off.png";
  const json rep_off = run_flow_view(dir, "1:5,2:click=panel.warped", off_png);
  CHECK_FALSE(has_panel(rep_off, "flow"));
  CHECK_FALSE(has_panel(rep_off, "warped"));
  const io::Image off = io::read_image(off_png);
  CHECK(changed(shot, off, flow_tile) > 0.5);
  CHECK(changed(shot, off, warped[0]) > 0.5);
  test::require_no_validation_messages();
  fs::remove_all(dir);
}

namespace {

// The keys of the LDI and residual run: both on, N = 3 (the shipped prior's 7 frames), the LDI
// network He-initialised (no pre-fit), so that it changes only near the view's events.
const std::vector<std::pair<std::string, std::string>> kLdiKeys = {
    {"iterations", "2"},     {"init_gaussians", "400"}, {"sh_degree", "0"},   {"mode", "blur"},
    {"virtual_frames", "3"}, {"densify", "false"},      {"seed", "3"},        {"lr_trajectory_init", "0.05"},
    {"ldi", "true"},         {"ldi_init_steps", "0"},   {"res_weight", "0.1"}};

std::vector<std::string> panel_ids(const json& frame) { return frame["panels"].get<std::vector<std::string>>(); }

// The largest |a - b| over the pixels of a crop's interior (the crop less `margin` pixels on each
// side that is not the sensor's edge): `full` is 3 x H x W, `part` 3 x crop.h x crop.w.
double crop_difference(const std::vector<float>& full, uint32_t W, uint32_t H, const std::vector<float>& part,
                       uint32_t cx, uint32_t cy, uint32_t cw, uint32_t ch, uint32_t margin) {
  double worst = 0;
  for (uint32_t c = 0; c < 3; ++c)
    for (uint32_t y = cy == 0 ? 0 : margin; y < (cy + ch == H ? ch : ch - margin); ++y)
      for (uint32_t x = cx == 0 ? 0 : margin; x < (cx + cw == W ? cw : cw - margin); ++x)
        worst = std::max(
            worst, std::abs(double(full[(size_t(c) * H + cy + y) * W + cx + x]) - part[(size_t(c) * ch + y) * cw + x]));
  return worst;
}

}  // namespace

TEST_CASE("train --view under Xvfb: the LDI and residual panels show the LDI frames and what L_res compares",
          "[viewer]") {
  require_xvfb();
  const fs::path dir = fresh_dir("ldi");
  const fs::path data_dir = write_dataset(dir);
  const fs::path shot_png = dir / "shot.png", report_json = dir / "report.json";
  std::string keys;
  for (auto& [k, v] : kLdiKeys) keys += " " + k + "=" + v;
  // Paused. Keys 7 and 8 hide both panels before frame 1; N steps once before frame 2, which
  // hides the loss plots (five terms: the check boxes would lie below the window's end); their
  // check boxes show the panels again in frame 3 (their content, fetched only while they are
  // shown, is then fetched at the same step).
  const Run r = run_evflow(dir, "train " + quote(data_dir.string()) + " --out " + quote((dir / "run").string()) + keys +
                                    " --view --view-width 800 --view-height 600 --view-paused --view-frames 3"
                                    " --view-script 1:7,1:8,2:n,2:click=plots,3:click=panel.ldi,3:click=panel.residual"
                                    " --view-fps-cap 0 --view-screenshot " +
                                    quote(shot_png.string()) + " --view-report " + quote(report_json.string()));
  INFO(r.out);
  REQUIRE(r.rc == 0);
  const json rep = json::parse(slurp(report_json));
  INFO(rep["frames"].dump(1));
  const std::vector<std::string> base{"blurry", "mid", "virtual", "events"};
  std::vector<std::string> all = base;
  all.insert(all.end(), {"ldi", "residual"});
  REQUIRE(rep["frames"].size() == 3);
  CHECK(panel_ids(rep["frames"][0]) == base);
  CHECK(panel_ids(rep["frames"][1]) == base);
  CHECK(panel_ids(rep["frames"][2]) == all);
  CHECK(rep["frames"][1]["step"] == 1);
  CHECK(rep["frames"][2]["step"] == 1);
  REQUIRE(rep["content"]["step"] == 1);
  CHECK(rep["content"]["ldi"]["frames"] == 7);
  CHECK(rep["content"]["residual"]["frames"] == std::vector<uint32_t>{0, 1, 2, 4, 5, 6});
  const io::Image shot = io::read_image(shot_png);

  // The same run in this process: one step, then the trainer's snapshot of view 0.
  auto& ctx = test::gpu_context();
  const io::Dataset data = io::load_dataset(data_dir);
  TrainConfig cfg;
  for (auto& [k, v] : kLdiKeys) cfg.set(k, v);
  Trainer t(ctx, data, cfg);
  t.step();
  const ViewSnapshot snap = t.snapshot(0, -1, {true, true});
  REQUIRE(snap.ldi_frames.size() == 7);
  REQUIRE(snap.has_residuals);
  int max_diff = 0;
  const json& lt = panel(rep, "ldi")["tiles"];
  REQUIRE(lt.size() == 7);
  for (size_t i = 0; i < 7; ++i) {
    std::vector<float> srgb = snap.ldi_frames[i];
    for (float& x : srgb) x = io::linear_to_srgb(x);
    CHECK(tile_match(shot, lt[i], srgb, &max_diff) >= 0.99);
  }
  // Tiles come in pairs on a row: the prior's R(t_i) beside the renders' F_i - F_N.
  const viewer::ResidualImages ri = viewer::residual_images(snap.residuals);
  const json& rt = panel(rep, "residual")["tiles"];
  REQUIRE(rt.size() == 12);
  for (size_t k = 0; k < 12; ++k) {
    CHECK(tile_match(shot, rt[k], ri.tiles[k], &max_diff) >= 0.99);
    if (k % 2 == 1) CHECK(rt[k]["y"] == rt[k - 1]["y"]);
  }
  CHECK(std::abs(rep["content"]["residual"]["scale"].get<double>() - ri.scale) <= 1e-6 * ri.scale);

  const uint32_t W = 96, H = 72;
  const std::vector<float> blurry = io::planar_rgb(data.train[0].blurry);
  {  // LDI frames: the training network's forward on a crop, and changed only near the view's events
    // The branch's own model on a 48 x 48 crop holding both events of view 0: equal on the
    // crop's interior (3 pixels, the network's reach, in from the sides inside the view).
    const ldi::Crop crop{6, 4, 48, 48};
    std::vector<float> part(size_t(3) * 48 * 48);
    for (uint32_t c = 0; c < 3; ++c)
      for (uint32_t y = 0; y < 48; ++y)
        for (uint32_t x = 0; x < 48; ++x)
          part[(size_t(c) * 48 + y) * 48 + x] = blurry[(size_t(c) * H + crop.y + y) * W + crop.x + x];
    gpu::Buffer part_buf(ctx, part.size() * 4, "blurry_crop");
    part_buf.write(part);
    gpu::Commands cmd(ctx);
    t.ldi()->model().forward(cmd, 0, t.ldi()->frame_times(0), crop, part_buf);
    cmd.submit();
    for (uint32_t i = 0; i < 7; ++i) {
      const double d = crop_difference(snap.ldi_frames[i], W, H, t.ldi()->model().frame(i).read<float>(part.size()),
                                       crop.x, crop.y, crop.w, crop.h, 3);
      INFO("frame " << i << ": largest difference " << d);
      CHECK(d <= 1e-6);
    }
    // Relative change C / B - 1 within the reach of an event pixel, and elsewhere.
    double near_events = 0, elsewhere = 0;
    for (uint32_t i = 0; i < 7; ++i)
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
          const bool close = (std::max(std::abs(int(x) - 10), std::abs(int(y) - 10)) <= 3) ||
                             (std::max(std::abs(int(x) - 40), std::abs(int(y) - 30)) <= 3);
          for (uint32_t c = 0; c < 3; ++c) {
            const size_t p = (size_t(c) * H + y) * W + x;
            const double rel = std::abs(snap.ldi_frames[i][p] / std::max(blurry[p], 1e-4f) - 1.0);
            double& worst = close ? near_events : elsewhere;
            worst = std::max(worst, rel);
          }
        }
    WARN("LDI frames vs the blurry image: up to " << near_events << " near the events, " << elsewhere << " elsewhere");
    CHECK(near_events > 0.1);
    CHECK(elsewhere < 0.01);
  }
  {  // residuals: the prior's prediction, and the renders' differences from the middle frame
    const auto prior = prior::predict_residuals(ctx, cfg.res_prior, data, snap.times).at(0);
    const size_t n = size_t(3) * W * H;
    REQUIRE(snap.residuals.prior.size() == 6);
    double prior_max = 0, render_max = 0, render_err = 0;
    std::vector<float> mid = snap.frames[3]->read<float>(n);
    for (float& x : mid) x = io::srgb_to_linear(x);
    for (size_t k = 0; k < 6; ++k) {
      CHECK(snap.residuals.prior[k] == std::vector<float>(prior.begin() + k * n, prior.begin() + (k + 1) * n));
      std::vector<float> f = snap.frames[snap.residuals.frames[k]]->read<float>(n);
      for (size_t j = 0; j < n; ++j) {
        const double want = double(io::srgb_to_linear(f[j])) - mid[j];
        render_err = std::max(render_err, std::abs(snap.residuals.renders[k][j] - want));
        render_max = std::max(render_max, std::abs(want));
        prior_max = std::max(prior_max, std::abs(double(snap.residuals.prior[k][j])));
      }
    }
    WARN("residuals: prior up to " << prior_max << "; renders up to " << render_max << ", off by " << render_err);
    // (One step moves the exposure trajectory a little: the renders' residuals are small yet.)
    CHECK(prior_max > 1e-2);
    CHECK(render_max > 1e-4);
    CHECK(render_err <= 1e-3 * render_max);
  }
  test::require_no_validation_messages();
  fs::remove_all(dir);
}
