// Adaptive density control (engine/densify): decisions, bookkeeping across every buffer, the
// optimizer state following its Gaussian, split sampling, the cap, the opacity reset.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "densify/densify_layout.h"
#include "densify/density_control.h"
#include "gpu_fixture.h"

using namespace evflow;
using namespace evflow::shaderio;

namespace {

constexpr float kLogDiv = 0.47000362924573558f;  // log(1.6)

struct Spec {
  float x, z;   // position (y = 0)
  float scale;  // isotropic-ish: scales (s, 0.5 s, 0.25 s)
  float opacity;
  float grad[3];  // grad2d norm per accumulation pass
};

float logit_of(double p) { return float(std::log(p / (1 - p))); }

GaussianCloud make_cloud(const std::vector<Spec>& specs) {
  GaussianCloud c;
  c.resize(specs.size(), 1);
  for (size_t i = 0; i < specs.size(); ++i) {
    const Spec& s = specs[i];
    c.means[3 * i] = s.x, c.means[3 * i + 1] = 1e-4f * float(i), c.means[3 * i + 2] = s.z;
    c.log_scales[3 * i] = std::log(0.25f * s.scale);
    c.log_scales[3 * i + 1] = std::log(s.scale);  // the largest
    c.log_scales[3 * i + 2] = std::log(0.5f * s.scale);
    // A distinct rotation per Gaussian (unnormalised).
    c.quats[4 * i] = 1.0f, c.quats[4 * i + 1] = 0.1f * float(i % 5), c.quats[4 * i + 2] = -0.2f,
                c.quats[4 * i + 3] = 0.05f * float(i);
    c.opacity_logits[i] = logit_of(s.opacity);
    for (int k = 0; k < 4; ++k)
      for (int ch = 0; ch < 3; ++ch) c.sh[(i * 4 + k) * 3 + ch] = float(i) + 0.1f * float(k) + 0.01f * float(ch);
  }
  return c;
}

// Adam groups as the trainer makes them.
std::unique_ptr<Adam> make_adam(gpu::Context& ctx, GaussianBuffers& p, GaussianBuffers& g) {
  auto adam = std::make_unique<Adam>(ctx);
  const uint32_t n = uint32_t(p.count);
  adam->add_group({"means", &p.means, &g.means, n * 3, 1e-3f, 3});
  adam->add_group({"log_scales", &p.log_scales, &g.log_scales, n * 3, 1e-3f, 3});
  adam->add_group({"quats", &p.quats, &g.quats, n * 4, 1e-3f, 4});
  adam->add_group({"opacity_logits", &p.opacity_logits, &g.opacity_logits, n, 1e-3f, 1});
  adam->add_group({"sh0", &p.sh[0], &g.sh[0], n * 3, 1e-3f, 3});
  adam->add_group({"sh1", &p.sh[1], &g.sh[1], n * 9, 1e-3f, 9});
  return adam;
}

// Distinct gradients per element, so that every row's Adam moments identify it.
void fill_grads(GaussianBuffers& g) {
  auto fill = [](gpu::Buffer& b, size_t n, float base) {
    std::vector<float> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = base * (1.0f + 0.37f * float(i));
    b.write(v);
  };
  const size_t n = g.count;
  fill(g.means, n * 3, 1e-3f);
  fill(g.log_scales, n * 3, 2e-3f);
  fill(g.quats, n * 4, 3e-3f);
  fill(g.opacity_logits, n, 4e-3f);
  fill(g.sh[0], n * 3, 5e-3f);
  fill(g.sh[1], n * 9, 6e-3f);
}

enum Kind { kOrig, kCopy, kChild };
struct Row {
  uint32_t src;
  Kind kind;
};

// Host reference of the rules (docs/density_control.md) with extent 1, for one Gaussian.
std::vector<Row> expected_rows(uint32_t i, const Spec& s, float max_radius, bool prune_big, const DensityConfig& cfg) {
  int vis = 0;
  float sum = 0;
  for (float g : s.grad)
    if (g > 0) sum += g, ++vis;
  const float mean = vis ? sum / float(vis) : 0.0f;
  const float smax = s.scale;
  const bool low = s.opacity < cfg.min_opacity;
  const bool big_screen = prune_big && max_radius > cfg.max_screen_radius;
  const bool big_world = prune_big && smax > cfg.max_world_scale;
  const bool child_big = prune_big && smax / cfg.split_divisor > cfg.max_world_scale;
  const bool keep = !(low || big_screen || big_world);
  std::vector<Row> rows;
  if (mean > cfg.grad_threshold && smax > cfg.percent_dense && !(low || child_big)) return {{i, kChild}, {i, kChild}};
  if (keep) rows.push_back({i, kOrig});
  if (mean > cfg.grad_threshold && smax <= cfg.percent_dense && !(low || big_world)) rows.push_back({i, kCopy});
  return rows;
}

// The hand-made cloud: one case per rule (camera at the origin looking down +z).
std::vector<Spec> cases() {
  return {
      {-1.0f, 5.0f, 0.005f, 0.5f, {1e-4f, 1e-4f, 1e-4f}},    // 0 keep: low gradient
      {-0.8f, 5.0f, 0.008f, 0.5f, {5e-4f, 5e-4f, 5e-4f}},    // 1 clone: small, high gradient
      {-0.6f, 5.0f, 0.05f, 0.5f, {5e-4f, 5e-4f, 5e-4f}},     // 2 split: large, high gradient
      {-0.4f, 5.0f, 0.005f, 0.003f, {0, 0, 0}},              // 3 prune: opacity < 0.005
      {-0.2f, 5.0f, 0.005f, 0.004f, {5e-4f, 5e-4f, 5e-4f}},  // 4 prune: low opacity beats growth
      {0.0f, 0.05f, 0.008f, 0.5f, {1e-4f, 1e-4f, 1e-4f}},    // 5 big on screen (radius > 20 px)
      {0.2f, 5.0f, 0.2f, 0.5f, {5e-4f, 5e-4f, 5e-4f}},       // 6 big in world; children too big
      {0.4f, 5.0f, 0.15f, 0.5f, {5e-4f, 5e-4f, 5e-4f}},      // 7 big in world; children fit
      {0.003f, 0.05f, 0.008f, 0.5f, {5e-4f, 5e-4f, 5e-4f}},  // 8 big on screen + clone: the copy lives
      {0.6f, 5.0f, 0.005f, 0.5f, {0, 0, 0}},                 // 9 never visible
      {0.8f, 5.0f, 0.005f, 0.5f, {2e-4f, 2e-4f, 2e-4f}},     // 10 mean == threshold: no growth
      {1.0f, 5.0f, 0.005f, 0.5f, {3e-4f, 3e-4f, 3e-4f}},     // 11 mean 3e-4: clone
      {1.2f, 5.0f, 0.05f, 0.5f, {4e-4f, 1e-4f, 0}},          // 12 sum 5e-4 over 2 passes: split
      {1.4f, 5.0f, 0.05f, 0.5f, {2.5e-4f, 1e-4f, 1.5e-4f}},  // 13 sum 5e-4 over 3 passes: keep
  };
}

Camera test_camera() {
  Camera cam;
  cam.width = cam.height = 64;
  cam.fx = cam.fy = 64;
  cam.cx = cam.cy = 32;
  return cam;
}

// Inria's screen radius in double (the kernel works in float: compare with a tolerance).
double host_radius(const GaussianCloud& c, size_t i, const Camera& cam) {
  const double z = c.means[3 * i + 2];
  // Rotation of the (normalised) quaternion.
  double q[4];
  double nq = 0;
  for (int k = 0; k < 4; ++k) nq += double(c.quats[4 * i + k]) * c.quats[4 * i + k];
  for (int k = 0; k < 4; ++k) q[k] = c.quats[4 * i + k] / std::sqrt(nq);
  const double w = q[0], x = q[1], y = q[2], zz = q[3];
  const double R[3][3] = {{1 - 2 * (y * y + zz * zz), 2 * (x * y - w * zz), 2 * (x * zz + w * y)},
                          {2 * (x * y + w * zz), 1 - 2 * (x * x + zz * zz), 2 * (y * zz - w * x)},
                          {2 * (x * zz - w * y), 2 * (y * zz + w * x), 1 - 2 * (x * x + y * y)}};
  double S[3][3] = {};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int k = 0; k < 3; ++k) S[a][b] += R[a][k] * R[b][k] * std::exp(2.0 * c.log_scales[3 * i + k]);
  const double px = c.means[3 * i], py = c.means[3 * i + 1];
  const double J[2][3] = {{cam.fx / z, 0, -cam.fx * px / (z * z)}, {0, cam.fy / z, -cam.fy * py / (z * z)}};
  double C[2][2] = {};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) C[a][b] += J[a][k] * S[k][l] * J[b][l];
  const double A = C[0][0] + 0.3, B = C[0][1], D = C[1][1] + 0.3;
  const double mid = 0.5 * (A + D), det = A * D - B * B;
  return std::ceil(3.0 * std::sqrt(mid + std::sqrt(std::max(0.1, mid * mid - det))));
}

struct Setup {
  GaussianCloud cloud;
  std::unique_ptr<GaussianBuffers> params, grads;
  std::unique_ptr<Adam> adam;
  DensityStats stats;
  explicit Setup(gpu::Context& ctx, GaussianCloud c) : cloud(std::move(c)), stats(ctx) {
    params = std::make_unique<GaussianBuffers>(ctx, cloud.size(), cloud.sh_degree, "p_");
    grads = std::make_unique<GaussianBuffers>(ctx, cloud.size(), cloud.sh_degree, "v_");
    params->upload(cloud);
    adam = make_adam(ctx, *params, *grads);
    fill_grads(*grads);
    gpu::Commands cmd(ctx);
    adam->step(cmd);  // nonzero moments that identify every row
    stats.reset(cmd, uint32_t(cloud.size()));
    cmd.submit();
    cloud = params->download();  // the parameters after that step
  }
};

uint32_t group_of(const Adam& a, const char* name) { return uint32_t(a.group_index(name)); }

}  // namespace

TEST_CASE("densify: prune / clone / split decisions follow the rules, every buffer follows", "[densify][gpu]") {
  auto& ctx = test::gpu_context();
  const auto specs = cases();
  const uint32_t n = uint32_t(specs.size());
  const Camera cam = test_camera();
  // mode 0: no big-pruning; 1: big-pruning; 2: big-pruning asked for with both limits 0 (off).
  for (int mode : {1, 0, 2}) {
    INFO("mode = " << mode);
    const bool prune_big = mode == 1;  // whether the big rules can fire
    Setup s(ctx, make_cloud(specs));
    DensityConfig dcfg;
    if (mode == 2) dcfg.max_screen_radius = 0, dcfg.max_world_scale = 0;
    DensityControl dc(ctx, dcfg);
    const DensityConfig& cfg = dc.config();
    gpu::Commands cmd(ctx);
    gpu::Buffer norms(ctx, n * 4, "norms");
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<float> v(n);
      for (uint32_t i = 0; i < n; ++i) v[i] = specs[i].grad[pass];
      norms.write(v);
      // Visibility by norm > 0 for these passes; the screen radius is checked first on a probe.
      if (pass == 0) {
        gpu::Buffer zeros(ctx, n * 4, "zeros");
        zeros.write(std::vector<float>(n, 0.0f));
        DensityStats probe(ctx);
        probe.reset(cmd, n);
        probe.accumulate(cmd, zeros, *s.params, cam);
        cmd.submit();
        auto radius = probe.max_radius().read<float>(n);
        auto vis = probe.vis_count().read<uint32_t>(n);
        for (uint32_t i = 0; i < n; ++i) {
          INFO("Gaussian " << i);
          REQUIRE(vis[i] == 1u);  // every case is in view
          REQUIRE(std::abs(radius[i] - host_radius(s.cloud, i, cam)) <= 1.0);
        }
        REQUIRE(radius[5] > 20.0f);
        REQUIRE(radius[8] > 20.0f);
        for (uint32_t i : {0u, 1u, 2u, 6u, 7u}) REQUIRE(radius[i] < 20.0f);
      }
      s.stats.accumulate(cmd, norms);
      cmd.submit();
    }
    // Screen radii into the statistics: a camera pass with zero norms (every case in view, so
    // each visibility count grows by one and the means are over passes + 1).
    gpu::Buffer zeros(ctx, n * 4, "zeros");
    zeros.write(std::vector<float>(n, 0.0f));
    s.stats.accumulate(cmd, zeros, *s.params, cam);
    cmd.submit();
    auto radius = s.stats.max_radius().read<float>(n);
    auto vis = s.stats.vis_count().read<uint32_t>(n);
    auto sums = s.stats.grad_sum().read<float>(n);

    // Expected rows (the mean divides by the visible passes, camera pass included).
    std::vector<Row> expect;
    for (uint32_t i = 0; i < n; ++i) {
      Spec sp = specs[i];
      int cnt = 0;
      double sum = 0;
      for (float g : sp.grad) cnt += g > 0, sum += g;
      REQUIRE(vis[i] == uint32_t(cnt + 1));
      REQUIRE(sums[i] == Approx(sum).margin(1e-9));
      const float mean = sums[i] / float(vis[i]);
      Spec eq = sp;
      eq.grad[0] = mean, eq.grad[1] = mean, eq.grad[2] = mean;
      if (mean == 0) eq.grad[0] = eq.grad[1] = eq.grad[2] = 0;
      for (auto r : expected_rows(i, eq, radius[i], prune_big, cfg)) expect.push_back(r);
    }

    // Before: parameters and moments.
    std::vector<std::vector<float>> m_before, v_before;
    for (size_t gi = 0; gi < s.adam->group_count(); ++gi) {
      m_before.push_back(s.adam->exp_avg(gi).read<float>(s.adam->group(gi).count));
      v_before.push_back(s.adam->exp_avg_sq(gi).read<float>(s.adam->group(gi).count));
    }
    const GaussianCloud before = s.cloud;

    auto res = dc.refine(cmd, *s.params, *s.grads, *s.adam, s.stats, 1.0f, mode != 0);
    const uint32_t m = uint32_t(expect.size());
    REQUIRE(res.before == n);
    REQUIRE(res.after == m);

    // Counts agree across every buffer.
    REQUIRE(s.params->count == m);
    REQUIRE(s.grads->count == m);
    REQUIRE(s.stats.count() == m);
    for (const GaussianBuffers* b : {s.params.get(), s.grads.get()}) {
      REQUIRE(b->means.size() >= m * 12ull);
      REQUIRE(b->log_scales.size() >= m * 12ull);
      REQUIRE(b->quats.size() >= m * 16ull);
      REQUIRE(b->opacity_logits.size() >= m * 4ull);
      REQUIRE(b->sh[0].size() >= m * 12ull);
      REQUIRE(b->sh[1].size() >= m * 36ull);
    }
    const uint32_t widths[6] = {3, 3, 4, 1, 3, 9};
    const gpu::Buffer* pbuf[6] = {&s.params->means,          &s.params->log_scales, &s.params->quats,
                                  &s.params->opacity_logits, &s.params->sh[0],      &s.params->sh[1]};
    const gpu::Buffer* gbuf[6] = {&s.grads->means,          &s.grads->log_scales, &s.grads->quats,
                                  &s.grads->opacity_logits, &s.grads->sh[0],      &s.grads->sh[1]};
    for (size_t gi = 0; gi < 6; ++gi) {
      REQUIRE(s.adam->group(gi).count == m * widths[gi]);
      REQUIRE(s.adam->group(gi).param == pbuf[gi]);
      REQUIRE(s.adam->group(gi).grad == gbuf[gi]);
      auto gz = gbuf[gi]->read<float>(m * widths[gi]);
      REQUIRE(std::all_of(gz.begin(), gz.end(), [](float x) { return x == 0.0f; }));
    }
    auto st_sum = s.stats.grad_sum().read<float>(m);
    auto st_vis = s.stats.vis_count().read<uint32_t>(m);
    REQUIRE(std::all_of(st_sum.begin(), st_sum.end(), [](float x) { return x == 0.0f; }));
    REQUIRE(std::all_of(st_vis.begin(), st_vis.end(), [](uint32_t x) { return x == 0u; }));

    // Rows by identity: the SH DC term names the source Gaussian.
    const GaussianCloud after = s.params->download();
    std::vector<std::vector<float>> m_after, v_after;
    for (size_t gi = 0; gi < 6; ++gi) {
      m_after.push_back(s.adam->exp_avg(gi).read<float>(m * widths[gi]));
      v_after.push_back(s.adam->exp_avg_sq(gi).read<float>(m * widths[gi]));
    }
    std::vector<float> child_means;
    for (uint32_t r = 0; r < m; ++r) {
      const uint32_t src = expect[r].src;
      const Kind kind = expect[r].kind;
      INFO("row " << r << " from Gaussian " << src << " kind " << int(kind));
      // Same-everything rows.
      for (int k = 0; k < 12; ++k) REQUIRE(after.sh[r * 12 + k] == before.sh[src * 12 + k]);
      for (int k = 0; k < 4; ++k) REQUIRE(after.quats[4 * r + k] == before.quats[4 * src + k]);
      REQUIRE(after.opacity_logits[r] == before.opacity_logits[src]);
      if (kind == kChild) {
        for (int k = 0; k < 3; ++k)
          REQUIRE(after.log_scales[3 * r + k] == Approx(before.log_scales[3 * src + k] - kLogDiv).margin(1e-6));
        // Inside the parent's 3-sigma ellipsoid: |diag(1/s) R^T (child - parent)| <= 3.
        double q[4], nq = 0;
        for (int k = 0; k < 4; ++k) nq += double(before.quats[4 * src + k]) * before.quats[4 * src + k];
        for (int k = 0; k < 4; ++k) q[k] = before.quats[4 * src + k] / std::sqrt(nq);
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                                {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                                {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
        double d2 = 0;
        for (int a = 0; a < 3; ++a) {
          double t = 0;
          for (int b = 0; b < 3; ++b) t += R[b][a] * (double(after.means[3 * r + b]) - before.means[3 * src + b]);
          t /= std::exp(double(before.log_scales[3 * src + a]));
          d2 += t * t;
        }
        REQUIRE(std::sqrt(d2) <= 3.0 + 1e-3);
        REQUIRE(std::sqrt(d2) > 0.0);
        for (int k = 0; k < 3; ++k) child_means.push_back(after.means[3 * r + k]);
      } else {
        for (int k = 0; k < 3; ++k) REQUIRE(after.means[3 * r + k] == before.means[3 * src + k]);
        for (int k = 0; k < 3; ++k) REQUIRE(after.log_scales[3 * r + k] == before.log_scales[3 * src + k]);
      }
      // Optimizer state: the original keeps its own; copies and children start at zero.
      for (size_t gi = 0; gi < 6; ++gi)
        for (uint32_t k = 0; k < widths[gi]; ++k) {
          const float em = kind == kOrig ? m_before[gi][src * widths[gi] + k] : 0.0f;
          const float ev = kind == kOrig ? v_before[gi][src * widths[gi] + k] : 0.0f;
          REQUIRE(m_after[gi][r * widths[gi] + k] == em);
          REQUIRE(v_after[gi][r * widths[gi] + k] == ev);
          if (kind == kOrig) REQUIRE(em != 0.0f);
        }
    }
    // The two children of a parent differ.
    for (size_t c = 0; c + 6 <= child_means.size(); c += 6)
      REQUIRE((child_means[c] != child_means[c + 3] || child_means[c + 1] != child_means[c + 4]));

    // The expected rule outcomes, spelled out.
    auto rows_of = [&](uint32_t i) {
      std::vector<Kind> k;
      for (auto& r : expect)
        if (r.src == i) k.push_back(r.kind);
      return k;
    };
    REQUIRE(rows_of(0) == std::vector<Kind>{kOrig});
    REQUIRE(rows_of(1) == std::vector<Kind>{kOrig, kCopy});
    REQUIRE(rows_of(2) == std::vector<Kind>{kChild, kChild});
    REQUIRE(rows_of(3).empty());
    REQUIRE(rows_of(4).empty());
    REQUIRE(rows_of(5) == (prune_big ? std::vector<Kind>{} : std::vector<Kind>{kOrig}));
    REQUIRE(rows_of(6) == (prune_big ? std::vector<Kind>{} : std::vector<Kind>{kChild, kChild}));
    REQUIRE(rows_of(7) == std::vector<Kind>{kChild, kChild});
    REQUIRE(rows_of(8) == (prune_big ? std::vector<Kind>{kCopy} : std::vector<Kind>{kOrig, kCopy}));
    REQUIRE(rows_of(9) == std::vector<Kind>{kOrig});

    // Decision words agree.
    auto dec = dc.decisions().read<uint32_t>(n);
    REQUIRE((dec[3] & kDecLowOpacity) != 0u);
    REQUIRE(((dec[5] & kDecBigScreen) != 0u) == prune_big);
    REQUIRE(((dec[6] & kDecBigWorld) != 0u) == prune_big);

    // The optimizer runs on the new buffers.
    fill_grads(*s.grads);
    s.adam->step(cmd);
    cmd.submit();
  }
  test::require_no_validation_messages();
}

TEST_CASE("densify: the mean gradient decides (threshold is strict), and refine is deterministic", "[densify][gpu]") {
  auto& ctx = test::gpu_context();
  const auto specs = cases();
  const uint32_t n = uint32_t(specs.size());
  std::vector<GaussianCloud> results;
  for (int run = 0; run < 2; ++run) {
    Setup s(ctx, make_cloud(specs));
    DensityControl dc(ctx);
    gpu::Commands cmd(ctx);
    gpu::Buffer norms(ctx, n * 4, "norms");
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<float> v(n);
      for (uint32_t i = 0; i < n; ++i) v[i] = specs[i].grad[pass];
      norms.write(v);
      s.stats.accumulate(cmd, norms);
      cmd.submit();
    }
    dc.refine(cmd, *s.params, *s.grads, *s.adam, s.stats, 1.0f, false);
    auto dec = dc.decisions().read<uint32_t>(n);
    REQUIRE((dec[10] & kDecGrown) == 0u);  // mean == 2e-4: not above
    REQUIRE((dec[11] & kDecGrown) != 0u);
    REQUIRE((dec[11] & kDecClone) != 0u);
    REQUIRE((dec[12] & kDecGrown) != 0u);  // 5e-4 over 2 visible passes
    REQUIRE((dec[12] & kDecSplit) != 0u);
    REQUIRE((dec[13] & kDecGrown) == 0u);  // 5e-4 over 3 visible passes
    REQUIRE((dec[9] & kDecGrown) == 0u);
    results.push_back(s.params->download());
  }
  REQUIRE(results[0].means == results[1].means);
  REQUIRE(results[0].log_scales == results[1].log_scales);
  REQUIRE(results[0].sh == results[1].sh);
  test::require_no_validation_messages();
}

TEST_CASE("densify: the cap grows the highest-gradient candidates only", "[densify][gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t n = 3000;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  std::vector<Spec> specs(n);
  for (uint32_t i = 0; i < n; ++i) {
    Spec& s = specs[i];
    s.x = U(rng) - 0.5f, s.z = 5.0f;
    s.scale = U(rng) < 0.5f ? 0.005f : 0.05f;   // clone or split
    s.opacity = U(rng) < 0.1f ? 0.001f : 0.5f;  // 10% pruned
    const float g = U(rng) < 0.6f ? 2.1e-4f + 1e-3f * U(rng) : 1e-4f * U(rng);
    s.grad[0] = g, s.grad[1] = s.grad[2] = 0;
  }
  for (uint32_t cap : {3400u, 2500u, 5000u, 7000u}) {
    INFO("cap " << cap);
    Setup s(ctx, make_cloud(specs));
    DensityConfig cfg;
    cfg.max_gaussians = cap;
    DensityControl dc(ctx, cfg);
    gpu::Commands cmd(ctx);
    gpu::Buffer norms(ctx, n * 4, "norms");
    std::vector<float> v(n);
    for (uint32_t i = 0; i < n; ++i) v[i] = specs[i].grad[0];
    norms.write(v);
    s.stats.accumulate(cmd, norms);
    auto res = dc.refine(cmd, *s.params, *s.grads, *s.adam, s.stats, 1.0f, false);

    // Host reference: base rows, candidates by descending gradient (ties by index), the head
    // whose running extra fits the budget.
    uint32_t base_total = 0;
    std::vector<uint32_t> extra(n, 0), cand;
    for (uint32_t i = 0; i < n; ++i) {
      const bool low = specs[i].opacity < cfg.min_opacity;
      base_total += low ? 0 : 1;
      if (!low && specs[i].grad[0] > cfg.grad_threshold) {
        extra[i] = 1;  // clone: + the copy; split: 2 children - the original
        cand.push_back(i);
      }
    }
    std::stable_sort(cand.begin(), cand.end(),
                     [&](uint32_t a, uint32_t b) { return specs[a].grad[0] > specs[b].grad[0]; });
    const uint32_t budget = cap > base_total ? cap - base_total : 0;
    std::vector<uint32_t> grown(n, 0);
    uint32_t run = 0, total = base_total;
    for (uint32_t i : cand) {
      if (run + extra[i] <= budget) grown[i] = 1, total += extra[i];
      run += extra[i];
    }
    REQUIRE(res.after == total);
    REQUIRE(res.after <= std::max(cap, base_total));
    if (cap >= 2 * n) REQUIRE(total == base_total + cand.size());
    auto dec = dc.decisions().read<uint32_t>(n);
    uint32_t mismatches = 0;
    for (uint32_t i = 0; i < n; ++i) mismatches += ((dec[i] & kDecGrown) != 0u) != (grown[i] != 0u);
    REQUIRE(mismatches == 0u);
    REQUIRE(s.params->count == res.after);
    REQUIRE(s.adam->group(0).count == res.after * 3);
  }
  test::require_no_validation_messages();
}

TEST_CASE("densify: opacity reset clamps to 0.01 and zeroes the opacity moments only", "[densify][gpu]") {
  auto& ctx = test::gpu_context();
  auto specs = cases();
  const uint32_t n = uint32_t(specs.size());
  specs[0].opacity = 0.9f, specs[1].opacity = 0.011f, specs[2].opacity = 0.0099f, specs[3].opacity = 0.001f;
  Setup s(ctx, make_cloud(specs));
  DensityControl dc(ctx);
  gpu::Commands cmd(ctx);
  const auto before = s.params->opacity_logits.read<float>(n);
  const uint32_t op = group_of(*s.adam, "opacity_logits"), mg = group_of(*s.adam, "means");
  const auto means_m = s.adam->exp_avg(mg).read<float>(n * 3);
  dc.reset_opacity(cmd, *s.params, *s.adam);
  cmd.submit();
  const auto after = s.params->opacity_logits.read<float>(n);
  const float cap = logit_of(0.01);
  for (uint32_t i = 0; i < n; ++i) {
    REQUIRE(after[i] == std::min(before[i], cap));
    REQUIRE(1.0 / (1.0 + std::exp(-double(after[i]))) <= 0.01 + 1e-7);
  }
  REQUIRE(after[3] == before[3]);
  const auto m = s.adam->exp_avg(op).read<float>(n), v = s.adam->exp_avg_sq(op).read<float>(n);
  REQUIRE(std::all_of(m.begin(), m.end(), [](float x) { return x == 0.0f; }));
  REQUIRE(std::all_of(v.begin(), v.end(), [](float x) { return x == 0.0f; }));
  REQUIRE(s.adam->exp_avg(mg).read<float>(n * 3) == means_m);
  test::require_no_validation_messages();
}

TEST_CASE("densify: schedule", "[densify]") {
  DensityConfig c;
  REQUIRE(!c.refine_at(400));
  REQUIRE(c.refine_at(500));
  REQUIRE(!c.refine_at(550));
  REQUIRE(c.refine_at(14900));
  REQUIRE(!c.refine_at(15000));
  REQUIRE(c.reset_at(3000));
  REQUIRE(!c.reset_at(0));
  REQUIRE(!c.prune_big_at(3000));
  REQUIRE(c.prune_big_at(3100));
}
