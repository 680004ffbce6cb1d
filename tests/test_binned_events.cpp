// Binned events (EBAD-NeRF's per-view signed counts): the intervals of the virtual frames take
// the bins they cover (exact on bin edges, proportional otherwise), drive the event loss as the
// stream they were binned from does, and train `blur+events` on an EBAD-style folder.
#include <unistd.h>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <regex>
#include <string>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "events/binned_events.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "io/llff.h"
#include "io/npy.h"
#include "loss/event_loss.h"
#include "plot/curve_plot.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

EventStream random_stream(uint32_t w, uint32_t h, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<double> t(n);
  for (auto& v : t) v = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  std::sort(t.begin(), t.end());
  EventStream ev;
  ev.width = w, ev.height = h;
  for (size_t i = 0; i < n; ++i)
    ev.push(uint16_t(rng() % w), uint16_t(rng() % h), t[i], (rng() % 3) ? int8_t(1) : int8_t(-1));
  return ev;
}

// The stream's net signed counts in `bins` equal bins of [0, 1): shape [1, bins, W*H].
std::vector<float> bin_stream(const EventStream& ev, uint32_t bins) {
  const size_t hw = size_t(ev.width) * ev.height;
  std::vector<float> c(bins * hw, 0.f);
  for (size_t i = 0; i < ev.size(); ++i)
    c[size_t(ev.t[i] * bins) * hw + size_t(ev.y[i]) * ev.width + ev.x[i]] += float(ev.p[i]);
  return c;
}

struct LossRun {
  double value;
  std::vector<float> counts;              // the loss's count planes as recorded
  std::vector<std::vector<float>> grads;  // per frame
};

// The event loss of F random frames over the window [0, 1) on `events`.
LossRun run_loss(const IntervalEvents& events, uint32_t F, uint64_t seed) {
  auto& ctx = test::gpu_context();
  const uint32_t W = events.width(), H = events.height();
  const size_t n = size_t(W) * H * 3;
  std::mt19937 rng(77);
  std::vector<gpu::Buffer> rgb, grad;
  for (uint32_t i = 0; i < F; ++i) {
    std::vector<float> img(n);
    for (auto& v : img) v = std::uniform_real_distribution<float>(0.05f, 0.95f)(rng);
    rgb.emplace_back(ctx, n * 4, "frame");
    rgb.back().write(img);
    grad.emplace_back(ctx, n * 4, "frame_grad");
    grad.back().write(std::vector<float>(n, 0.f));
  }
  EventLoss loss(ctx, events, 1.0f);
  ExposureFrames f;
  f.width = W, f.height = H, f.t0 = 0.0, f.t1 = 1.0, f.seed = seed;
  f.u = ExposureTrajectory::virtual_times(int(F - 1) / 2);
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&rgb[i]), f.grad.push_back(&grad[i]);
  gpu::Commands cmd(ctx);
  loss.record(cmd, f);
  cmd.submit();
  LossRun r{loss.value(), {}, {}};
  const size_t planes = size_t(F - 1) * 2 * W * H;
  if (events.float_planes())
    r.counts = loss.counts().read<float>(planes);
  else
    for (uint32_t c : loss.counts().read<uint32_t>(planes)) r.counts.push_back(float(c));
  for (auto& g : grad) r.grads.push_back(g.read<float>(n));
  return r;
}

}  // namespace

TEST_CASE("binned events: an interval takes the bins it covers, whole on bin edges, in proportion otherwise",
          "[events]") {
  const EventWindow w{0.0, 1.0};
  auto one = bin_weights(1.0 / 3, 0.5, w, 6);  // 2/6 .. 3/6: bin 2 exactly, despite rounding in 1/3 * 6
  REQUIRE(one.size() == 1);
  CHECK(one[0].bin == 2);
  CHECK(one[0].weight == 1.0);
  auto two = bin_weights(0.1, 0.35, w, 4);  // 0.4 .. 1.4 bins
  REQUIRE(two.size() == 2);
  CHECK(two[0].bin == 0);
  CHECK(two[0].weight == Approx(0.6));
  CHECK(two[1].bin == 1);
  CHECK(two[1].weight == Approx(0.4));
  auto clamped = bin_weights(-1.0, 0.25, w, 4);
  REQUIRE(clamped.size() == 1);
  CHECK(clamped[0].weight == 1.0);
  CHECK(bin_weights(0.5, 0.25, w, 4).empty());                         // reversed: nothing
  CHECK(bin_weights(2.0, 3.0, EventWindow{2.0, 4.0}, 3)[0].bin == 0);  // a window not at 0
  CHECK(bin_weights(3.0, 4.0, EventWindow{2.0, 4.0}, 4).size() == 2);  // bins 2 and 3
}

TEST_CASE("binned events: on bin edges the event loss equals the stream's, between edges the bins are shared",
          "[events][loss]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 20, H = 14, F = 7;  // 6 intervals of [0, 1)
  const EventStream ev = random_stream(W, H, 5000, 5);
  GpuEvents stream(ctx, ev, {EventWindow{0.0, 1.0}}, "test stream");
  const LossRun ref = run_loss(stream, F, 3);
  for (uint32_t bins : {6u, 12u}) {  // one and two bins per interval: the net counts are exact
    INFO(bins << " bins");
    BinnedEvents binned(ctx, bin_stream(ev, bins), bins, W, H, {EventWindow{0.0, 1.0}}, "test bins");
    const LossRun got = run_loss(binned, F, 3);
    CHECK(got.value == Approx(ref.value).epsilon(1e-6));
    for (uint32_t i = 0; i < F; ++i)
      for (size_t k = 0; k < got.grads[i].size(); k += 37)
        REQUIRE(got.grads[i][k] == Approx(ref.grads[i][k]).margin(1e-7).epsilon(1e-4));
  }
  // 4 bins under 6 intervals: interval k takes each bin in proportion to the length it covers.
  const std::vector<float> c4 = bin_stream(ev, 4);
  BinnedEvents binned(ctx, c4, 4, W, H, {EventWindow{0.0, 1.0}}, "test bins");
  const LossRun got = run_loss(binned, F, 3);
  const auto u = ExposureTrajectory::virtual_times(3);
  const size_t hw = size_t(W) * H;
  for (size_t k = 0; k + 1 < u.size(); ++k) {
    std::vector<double> pos(hw, 0), neg(hw, 0);
    for (uint32_t b = 0; b < 4; ++b) {  // the overlap of [u_k, u_k+1) with bin b, in bins
      const double w = std::max(0.0, std::min(u[k + 1], (b + 1) / 4.0) - std::max(u[k], b / 4.0)) * 4;
      for (size_t p = 0; p < hw; ++p) {
        pos[p] += w * std::max(0.f, c4[b * hw + p]);
        neg[p] += w * std::max(0.f, -c4[b * hw + p]);
      }
    }
    for (size_t p = 0; p < hw; ++p) {
      REQUIRE(got.counts[k * 2 * hw + p] == Approx(pos[p]).margin(1e-5));
      REQUIRE(got.counts[k * 2 * hw + hw + p] == Approx(neg[p]).margin(1e-5));
    }
  }
  CHECK(std::isfinite(got.value));
  CHECK_THROWS_WITH(BinnedEvents(ctx, c4, 5, W, H, {EventWindow{0.0, 1.0}}, "some.npy"),
                    Catch::Contains("some.npy") && Catch::Contains("5 bins"));
  test::require_no_validation_messages();
}

TEST_CASE("binned events: views with the same window keep their own counts, kept or shared", "[events][loss]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 12, H = 8, F = 7, bins = 6;
  std::vector<float> counts = bin_stream(random_stream(W, H, 800, 8), bins);
  const std::vector<float> second = bin_stream(random_stream(W, H, 800, 9), bins);
  counts.insert(counts.end(), second.begin(), second.end());  // shape [2, bins, W*H]
  const EventWindow w{0.0, 1.0};
  BinnedEvents binned(ctx, counts, bins, W, H, {w, w}, "test bins");
  const size_t n = size_t(W) * H * 3, planes = size_t(F - 1) * 2 * W * H;
  std::vector<gpu::Buffer> rgb;
  for (uint32_t i = 0; i < F; ++i) {
    rgb.emplace_back(ctx, n * 4, "frame");
    rgb.back().write(std::vector<float>(n, 0.5f));
  }
  ExposureFrames f;
  f.width = W, f.height = H, f.t0 = w.t0, f.t1 = w.t1;
  f.u = ExposureTrajectory::virtual_times(3);
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&rgb[i]);
  gpu::Commands cmd(ctx);
  auto counts_of = [&](EventLoss& loss, uint32_t view) {
    f.view = view;
    loss.record_value(cmd, f);
    cmd.submit();
    return loss.counts().read<float>(planes);
  };
  EventLoss fresh(ctx, binned, 1.0f);
  const std::vector<float> view1 = counts_of(fresh, 1);
  EventLossOptions none;
  none.count_cache_bytes = 0;
  for (const EventLossOptions& o : {EventLossOptions{}, none}) {
    INFO("count_cache_bytes " << o.count_cache_bytes);
    EventLoss loss(ctx, binned, 1.0f, o);
    const std::vector<float> view0 = counts_of(loss, 0);
    CHECK(view0 != view1);
    CHECK(counts_of(loss, 1) == view1);
    CHECK(counts_of(loss, 0) == view0);
  }
  test::require_no_validation_messages();
}

namespace {

// An EBAD-NeRF folder made by hand from a simulated dataset in our layout: poses_bounds.npy
// (every 8th row a test view), images/ and images_gt_blur/ of the training views,
// images_gt_novel/ of the test views, and events.npy: each training view's events as net signed
// counts in `bins` equal bins of its exposure.
void write_ebad_folder(const io::Dataset& d, const fs::path& out, uint32_t bins) {
  const size_t T = d.train.size();
  size_t N = T;
  while (N - (N + 7) / 8 < T) ++N;
  std::vector<Camera> cams;
  size_t next_train = 0, next_novel = 0;
  for (size_t i = 0; i < N; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "r_%03zu.png", i);
    if (i % 8 == 0) {
      const io::View& v = d.novel.at(next_novel++ % d.novel.size());
      cams.push_back(v.camera);
      io::write_image(out / "images_gt_novel" / name, *v.sharp_mid);
    } else {
      const io::View& v = d.train[next_train++];
      cams.push_back(v.camera);
      io::write_image(out / "images" / name, v.blurry);
      io::write_image(out / "images_gt_blur" / name, *v.sharp_mid);
    }
  }
  io::write_poses_bounds(out / "poses_bounds.npy", cams, std::vector<double>(N, d.near), std::vector<double>(N, d.far));
  const size_t hw = size_t(d.events.width) * d.events.height;
  std::vector<float> counts(T * bins * hw, 0.f);
  for (size_t v = 0; v < T; ++v) {
    const double t0 = d.train[v].exposure_start, t1 = d.train[v].exposure_end;
    auto [a, b] = d.events.window(t0, t1);
    for (size_t i = a; i < b; ++i) {
      const size_t bin = std::min<size_t>(bins - 1, size_t((d.events.t[i] - t0) / (t1 - t0) * bins));
      counts[(v * bins + bin) * hw + size_t(d.events.y[i]) * d.events.width + d.events.x[i]] += float(d.events.p[i]);
    }
  }
  io::write_npy(out / "events.npy", {T, size_t(bins), hw}, counts);
}

}  // namespace

TEST_CASE("binned events: blur+events trains on an EBAD-NeRF folder, its event term on every step",
          "[events][train][gpu]") {
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_ebad_train");
  std::string out;
  REQUIRE(test::run_evflow(dir, "simulate --scene gallery --out sim --width 32 --height 24 --blur-px 4 --seed 3",
                           out) == 0);
  const io::Dataset sim = io::load_dataset(dir / "sim");
  REQUIRE(sim.events.size() > 0);
  write_ebad_folder(sim, dir / "ebad", 4);
  const io::Dataset ebad = io::load_dataset(dir / "ebad");
  REQUIRE(ebad.layout == "ebad");
  REQUIRE(ebad.train.size() == sim.train.size());
  // 4 intervals over 4 bins: edges aligned. Equal thresholds: the bins' net counts give the
  // stream's event side exactly.
  const std::string args =
      " --out RUN method=blur+events event_from=0 iterations=6 virtual_frames=2 init_gaussians=300 "
      "max_gaussians=600 sh_degree=0 event_theta_pos=0.25 event_theta_neg=0.25";
  auto train = [&](const std::string& data, const std::string& run) {
    const std::string a = "train " + data + std::regex_replace(args, std::regex("RUN"), run);
    const int rc = test::run_evflow(dir, a, out);
    INFO(a << "\n" << out);
    REQUIRE(rc == 0);
    return plot::read_curve_csv(dir / run / "curve.csv");
  };
  const plot::CurveTable t = train("ebad", "run");
  const int events = t.column("events");
  REQUIRE(events >= 0);
  REQUIRE(t.rows.size() == 6);
  double lo = 1e9, hi = -1e9;
  for (const auto& row : t.rows) {
    const double e = row[size_t(events)];
    CHECK(std::isfinite(e));
    CHECK(e > 0);
    lo = std::min(lo, e), hi = std::max(hi, e);
  }
  CHECK(hi > lo);  // a value of its own per view and step
  // The same first step on the simulated folder, from its event stream: the same event term (the
  // folders differ only in the poses' last rounding).
  const plot::CurveTable s = train("sim", "stream");
  const int l1 = t.column("l1_ssim");
  CHECK(t.rows[0][size_t(l1)] == Approx(s.rows[0][size_t(l1)]).epsilon(1e-4));
  CHECK(t.rows[0][size_t(events)] == Approx(s.rows[0][size_t(events)]).epsilon(1e-3));
  fs::remove_all(dir);
}
