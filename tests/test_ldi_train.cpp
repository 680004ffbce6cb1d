// The LDI branch in the trainer (engine/train/ldi_branch.h): the joint loss's gradient reaches
// both the LDI's weights and the splats (the gradient a step applies against central differences
// of the step's total loss, on a tiny case), a short run with every LDI term on changes the
// network and the splats with finite losses, the branch's state round-trips through a
// checkpoint, and joint_ldi_share scales only the network's side of L_joint.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numeric>
#include <set>

#include "camera/trajectory.h"
#include "events/edi.h"
#include "events/event_model.h"
#include "exposure_sim.h"
#include "gpu_fixture.h"
#include "splat/synthetic.h"
#include "train/synthetic_dataset.h"
#include "train/trainer.h"
#include "train/training_data.h"

using namespace evflow;

namespace {

constexpr uint32_t W = 48, H = 32;
constexpr float kGrey = 0.35f;

// Three views of a drifting cloud: blurry images (linear mean of 17 renders) and their events.
// The drifting cloud's ground truth.
GaussianCloud drift_truth() {
  return synthetic_cloud(42, 200, 0, Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0}));
}

io::Dataset drift_dataset(gpu::Context& ctx) {
  const GaussianCloud truth = drift_truth();
  io::Dataset data = render_synthetic_dataset(ctx, W, H, 3, 0, truth.size());
  GaussianBuffers gt(ctx, truth.size(), truth.sh_degree, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  RenderState state(ctx);
  data.events.width = W, data.events.height = H;
  for (size_t v = 0; v < data.train.size(); ++v) {
    ExposureTrajectory motion(data.train[v].camera, 0, 0.0);
    for (int j = 0; j < ExposureTrajectory::kKnots; ++j) motion.data()[j * 6] = 0.12 * (j - 4) / 4.0;
    test::simulate_exposure(r, state, gt, data, v, motion, 0.1 * v, 0.04, 16, 3 + v, kGrey);
  }
  data.events.validate("test events");
  return data;
}

TrainConfig ldi_config() {
  TrainConfig cfg;
  cfg.apply_method("blur-only");
  cfg.virtual_frames = 1;
  cfg.sh_degree = 0;
  cfg.background = {kGrey, kGrey, kGrey};
  cfg.densify = false;
  cfg.iterations = 20;
  cfg.event_from = 0.0;
  cfg.joint_from = 0.0;
  cfg.ldi = true;
  cfg.ldi_widths = {32, 8, 1};
  cfg.ldi_crop = 24;
  cfg.ldi_init_steps = 0;
  return cfg;
}

std::vector<size_t> largest(const std::vector<double>& g, size_t n) {
  std::vector<size_t> idx(g.size());
  std::iota(idx.begin(), idx.end(), size_t(0));
  std::partial_sort(idx.begin(), idx.begin() + n, idx.end(),
                    [&](size_t a, size_t b) { return std::abs(g[a]) > std::abs(g[b]); });
  idx.resize(n);
  return idx;
}

nn::NamedTensor& tensor(nn::SafetensorsFile& f, const std::string& name) {
  for (auto& t : f.tensors)
    if (t.name == name) return t;
  FAIL("no tensor " << name);
  return f.tensors[0];
}

}  // namespace

TEST_CASE("LDI branch: the joint loss's gradient reaches the LDI weights and the splats", "[gpu][train][ldi]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  REQUIRE(data.events.size() > 100);
  TrainConfig cfg = ldi_config();
  cfg.ldi_blur_weight = 0;  // the joint loss alone on the LDI
  cfg.ldi_event_weight = 0;
  cfg.ldi_anchor_weight = 0;  // its value is not in the step's loss
  Checkpoint start{0, drift_truth(), {}};
  for (size_t i = 0; i < start.cloud.sh.size(); ++i) start.cloud.sh[i] += 0.3f * float((i % 7) / 6.0 - 0.5);
  start.ldi = Trainer(ctx, data, cfg).checkpoint().ldi;  // the He-initialised network
  start.step = 0;

  Trainer t(ctx, data, cfg, start);
  REQUIRE(t.losses().size() == 3);  // blur, ldi_blur, joint
  const StepStats st = t.step();
  REQUIRE_FALSE(st.skipped);
  REQUIRE(st.term_values[2] > 0.0);
  const GaussianCloud g = t.last_gradients();
  std::vector<double> gw;  // the LDI's applied gradient: layer 0's weights, then layer 1's bias
  for (size_t l = 0; l < 2; ++l) {
    const auto w = l == 0 ? t.ldi()->model().network().layer(0).weight_grad().read<float>(32 * 8 * 9)
                          : t.ldi()->model().network().layer(1).bias_grad().read<float>(1);
    gw.insert(gw.end(), w.begin(), w.end());
  }

  auto loss_with = [&](const std::function<void(Checkpoint&)>& perturb) {
    Checkpoint c = start;
    perturb(c);
    Trainer p(ctx, data, cfg, c);
    const StepStats s = p.step();
    REQUIRE(s.view == st.view);
    return s.loss;
  };
  auto check = [&](const char* what, size_t index, double analytic, double h,
                   const std::function<void(Checkpoint&, double)>& add) {
    double num = 0, den = 0;  // the least-squares slope of symmetric differences at +-h .. +-3h
    for (int k = 1; k <= 3; ++k) {
      const double lp = loss_with([&](Checkpoint&c) { add(c, +k * h); }),
                   lm = loss_with([&](Checkpoint&c) { add(c, -k * h); });
      num += k * (lp - lm);
      den += 2.0 * k * k * h;
    }
    const double fd = num / den;
    std::printf("LDI step gradient %s[%zu]: applied %.6g, central difference %.6g\n", what, index, analytic, fd);
    CHECK(std::abs(analytic - fd) <= 2e-2 * std::abs(fd));
  };
  // The splats: colours with the largest gradients (the joint loss adds to the blur term's).
  const std::vector<double> gs(g.sh.begin(), g.sh.end());
  for (size_t i : largest(gs, 2))
    check("sh", i, gs[i], 1e-2, [&](Checkpoint& c, double d) { c.cloud.sh[i] += float(d); });
  // The network: its output bias and the largest first-layer weights.
  check("ldi.1.bias", 0, gw.back(), 1e-2,
        [&](Checkpoint& c, double d) { tensor(*c.ldi, "ldi.1.bias").values[0] += float(d); });
  for (size_t i : largest(std::vector<double>(gw.begin(), gw.end() - 1), 2))
    check("ldi.0.weight", i, gw[i], 1e-2,
          [&](Checkpoint& c, double d) { tensor(*c.ldi, "ldi.0.weight").values[i] += float(d); });
  test::require_no_validation_messages();
}

TEST_CASE("LDI branch: a short run with every term changes the network and the splats, and its state round-trips",
          "[gpu][train][ldi]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  TrainConfig cfg = ldi_config();
  cfg.ldi_init_steps = 20;
  Trainer t(ctx, data, cfg);
  const std::vector<float> w0 = t.ldi()->model().network().layer(0).weight_values();
  const GaussianCloud c0 = t.cloud();
  REQUIRE(t.losses().size() == 4);  // blur, ldi_blur, ldi_events, joint
  for (int s = 0; s < 6; ++s) {
    const StepStats st = t.step();
    REQUIRE_FALSE(st.skipped);
    for (double v : st.term_values) REQUIRE(std::isfinite(v));
    CHECK(st.term_values[2] > 0.0);  // the event term on the LDI frames took part
    if (ctx.caps().timestamps) {     // every stage of the branch has its time (bench train prints them)
      std::set<std::string> names;
      for (const auto& [name, ms] : st.ldi_stages) {
        names.insert(name);
        REQUIRE(ms >= 0.0);
      }
      for (const char* stage : {"ldi crops", "ldi event tensors", "ldi conv 0", "ldi conv 1", "ldi frames",
                                "ldi blur term", "ldi joint term", "ldi event term", "ldi joint to renders",
                                "ldi conv backward 1", "ldi conv backward 0", "ldi adam"})
        CHECK(names.count(stage) == 1);
    }
  }
  CHECK(t.ldi()->model().network().layer(0).weight_values() != w0);
  CHECK(t.cloud().sh != c0.sh);

  // The whole-view frames: a subset, in the order asked, equals those frames of the full set.
  gpu::Commands cmd(ctx);
  const auto all = t.ldi()->view_frames(cmd, 1), some = t.ldi()->view_frames(cmd, 1, {2, 0});
  REQUIRE(all.size() == cfg.virtual_frames * 2 + 1);
  REQUIRE(some.size() == 2);
  CHECK(some[0] == all[2]);
  CHECK(some[1] == all[0]);
  CHECK(all[2] != all[0]);

  // The checkpoint's LDI state continues the run bit-identically.
  const Checkpoint ck = t.checkpoint();
  REQUIRE(ck.ldi);
  Trainer resumed(ctx, data, cfg, ck);
  const StepStats a = t.step(), b = resumed.step();
  CHECK(a.loss == b.loss);
  CHECK(t.ldi()->model().network().layer(0).weight_values() ==
        resumed.ldi()->model().network().layer(0).weight_values());
  Checkpoint missing = ck;
  missing.ldi.reset();
  CHECK_THROWS_WITH(Trainer(ctx, data, cfg, missing), Catch::Contains("ldi.safetensors"));
  TrainConfig plain = cfg;
  plain.mode = TrainMode::Plain;
  CHECK_THROWS_WITH(Trainer(ctx, data, plain), Catch::Contains("needs mode=blur"));
  test::require_no_validation_messages();
}

TEST_CASE("LDI branch: L_ev^ldi trains from the first step, L_joint reaches the splats only from joint_from",
          "[gpu][train][ldi]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  TrainConfig cfg = ldi_config();
  cfg.iterations = 4;
  cfg.event_from = 0.5;
  cfg.joint_from = 0.5;  // steps 2 and 3
  TrainConfig off = cfg;
  off.ldi = false;
  Trainer t(ctx, data, cfg), without(ctx, data, off);
  for (uint32_t s = 0; s < 4; ++s) {
    INFO("step " << s);
    const StepStats st = t.step();
    without.step();
    CHECK(st.term_values[2] > 0.0);                                         // ldi_events, before event_from too
    CHECK((st.term_values[3] > 0.0) == (s >= 2));                           // joint
    if (s < 2) CHECK(test::same_values(t.cloud().sh, without.cloud().sh));  // the branch leaves the splats alone
  }
  CHECK_FALSE(test::same_values(t.cloud().sh, without.cloud().sh));
  test::require_no_validation_messages();
}

TEST_CASE("LDI branch: after an EDI warm-up, from the first blur step, L_joint from joint_from of the blur steps",
          "[gpu][train][ldi][warmup]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  TrainConfig cfg = ldi_config();
  cfg.iterations = 6;
  cfg.edi_warmup = 0.5;  // steps 1-3 fit the EDI images
  cfg.joint_from = 0.5;  // of the three blur steps: from step 5 (4.5 rounded down, then the next step)
  Trainer t(ctx, data, cfg);
  const std::vector<float> w0 = t.ldi()->model().network().layer(0).weight_values();
  for (uint32_t s = 0; s < 6; ++s) {
    INFO("step " << s + 1);
    const StepStats st = t.step();
    REQUIRE(st.term_values.size() == 4);  // blur, ldi_blur, ldi_events, joint
    CHECK_FALSE(st.skipped);              // the branch's terms, not recorded in a warm-up step, read 0
    CHECK(std::isfinite(st.loss));
    const bool warm = s < 3;
    CHECK((st.ldi_ms > 0.0) == !warm);
    CHECK((st.term_values[1] > 0.0) == !warm);  // ldi_blur
    CHECK((st.term_values[2] > 0.0) == !warm);  // ldi_events
    CHECK((st.term_values[3] > 0.0) == (s >= 4));
    const bool moved = t.ldi()->model().network().layer(0).weight_values() != w0;
    CHECK(moved == !warm);  // warm-up steps leave the network as it was
  }
  test::require_no_validation_messages();
}

TEST_CASE("LDI branch: joint_ldi_share scales the network's side of L_joint and leaves the renders' side as it is",
          "[gpu][train][ldi]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  TrainConfig both = ldi_config();  // L_joint from the first step
  TrainConfig splats_only = both, no_joint = both, half = both;
  splats_only.joint_ldi_share = 0.0;
  half.joint_ldi_share = 0.5;
  no_joint.joint_weight = 0.0;
  Trainer a(ctx, data, both), b(ctx, data, splats_only), c(ctx, data, no_joint), d(ctx, data, half);
  for (Trainer* t : {&a, &b, &c, &d}) {
    const StepStats st = t->step();
    REQUIRE(st.term_values.size() == 4);  // blur, ldi_blur, ldi_events, joint
    CHECK(st.term_values[3] > 0.0);       // L_joint on from the first step (its value is unweighted)
  }
  auto weights = [](Trainer& t) { return t.ldi()->model().network().layer(0).weight_values(); };
  CHECK(weights(b) == weights(c));  // share 0: the network learns from its own terms alone
  CHECK(weights(a) != weights(c));
  CHECK(weights(d) != weights(c));
  CHECK(weights(d) != weights(a));
  CHECK(test::same_values(a.cloud().sh, b.cloud().sh));  // the renders' side does not depend on it
  CHECK_FALSE(test::same_values(b.cloud().sh, c.cloud().sh));
  TrainConfig bad = both;
  for (double s : {-0.1, 1.5, std::nan("")}) {
    bad.joint_ldi_share = s;
    CHECK_THROWS_WITH(Trainer(ctx, data, bad), Catch::Contains("joint_ldi_share must be in [0, 1]"));
  }
  test::require_no_validation_messages();
}

namespace {

// The mean over view 0's pixels and the branch's frame times of (log E - log D)^2, E the LDI's
// double integral over the whole view (from its frames: E = B / C), D EDI's with the branch's
// thresholds.
double anchor_error(gpu::Context& ctx, Trainer& t, const io::Dataset& data, const TrainConfig& cfg) {
  gpu::Commands cmd(ctx);
  const std::vector<std::vector<float>> frames = t.ldi()->view_frames(cmd, 0);
  const auto [pos, neg] = event_thresholds(data, cfg);
  const io::View& v = data.train[0];
  const events::EdiIntegrator edi(data.events, v.exposure_start, v.exposure_end, {pos, neg, {}, {}});
  const std::vector<double> times = t.ldi()->frame_times(0);
  const std::vector<float> blurry = io::planar_rgb(v.blurry);
  double s = 0;
  size_t n = 0;
  for (size_t i = 0; i < times.size(); ++i) {
    const std::vector<double> d = edi.double_integral(times[i]);
    for (size_t p = 0; p < d.size(); ++p, ++n)
      s += std::pow(std::log(double(blurry[p]) / frames[i][p]) - std::log(d[p]), 2);
  }
  return s / double(n);
}

}  // namespace

TEST_CASE("LDI branch: the anchor draws the network to EDI's double integral, and nothing else does here",
          "[gpu][train][ldi]") {
  auto& ctx = test::gpu_context();
  const io::Dataset data = drift_dataset(ctx);
  TrainConfig off = ldi_config();  // He initialisation, no pre-fit
  off.ldi_blur_weight = off.ldi_event_weight = off.joint_weight = off.ldi_anchor_weight = 0.0;
  off.ldi_lr = 1e-2;
  TrainConfig on = off;
  on.ldi_anchor_weight = 1.0;
  Trainer a(ctx, data, on), b(ctx, data, off);
  const double start = anchor_error(ctx, a, data, on);
  REQUIRE(start == Approx(anchor_error(ctx, b, data, off)));
  for (int s = 0; s < 20; ++s) a.step(), b.step();
  const double anchored = anchor_error(ctx, a, data, on), free = anchor_error(ctx, b, data, off);
  INFO("log-E error to EDI: " << start << " at the start, " << anchored << " anchored, " << free << " without");
  CHECK(free == Approx(start));
  CHECK(anchored < 0.5 * start);
  TrainConfig bad = on;
  for (double w : {-1.0, std::nan("")}) {
    bad.ldi_anchor_weight = w;
    CHECK_THROWS_WITH(Trainer(ctx, data, bad), Catch::Contains("ldi_anchor_weight must be a finite weight >= 0"));
  }
  test::require_no_validation_messages();
}
