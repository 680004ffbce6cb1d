#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "optim/adam.h"
#include "optim/schedule.h"

using namespace evflow;

namespace {

// Double-precision Adam (PyTorch's formulation) over one group. The scales are the natural
// magnitudes of each result for relative errors: b1|m| + (1-b1)|g| for m, v itself for v, and
// |p| + |update| for p (a result near zero by cancellation is judged against its terms).
struct RefAdam {
  std::vector<double> p, m, v;
  std::vector<double> sp, sm, sv;
  uint64_t t = 0;
  void step(const std::vector<float>& g, double lr, double b1 = 0.9, double b2 = 0.999, double eps = 1e-15) {
    ++t;
    const double bc1 = 1 - std::pow(b1, double(t)), bc2 = 1 - std::pow(b2, double(t));
    sp.resize(p.size()), sm.resize(p.size()), sv.resize(p.size());
    for (size_t i = 0; i < p.size(); ++i) {
      sm[i] = b1 * std::abs(m[i]) + (1 - b1) * std::abs(g[i]);
      m[i] = b1 * m[i] + (1 - b1) * g[i];
      v[i] = b2 * v[i] + (1 - b2) * double(g[i]) * g[i];
      sv[i] = v[i];
      const double upd = lr * (m[i] / bc1) / (std::sqrt(v[i] / bc2) + eps);
      sp[i] = std::abs(p[i]) + std::abs(upd);
      p[i] -= upd;
    }
  }
};

std::vector<float> random_floats(size_t n, std::mt19937& rng, float scale) {
  std::normal_distribution<float> d(0.0f, scale);
  std::vector<float> v(n);
  for (auto& x : v) x = d(rng);
  return v;
}

// Max of |gpu - ref| / scale (0 where both are 0).
double max_rel(const std::vector<float>& gpu, const std::vector<double>& ref, const std::vector<double>& scale) {
  double e = 0;
  for (size_t i = 0; i < gpu.size(); ++i) {
    const double d = std::abs(double(gpu[i]) - ref[i]);
    if (d > 0) e = std::max(e, d / scale[i]);
  }
  return e;
}

}  // namespace

TEST_CASE("adam: first step is lr * sign(g) (bias correction), per-group learning rates", "[gpu][optim]") {
  auto& ctx = test::gpu_context();
  std::mt19937 rng(1);
  const uint32_t n0 = 999, n1 = 300;  // n1: 100 rows of 3
  gpu::Buffer p0(ctx, n0 * 4, "p0"), g0(ctx, n0 * 4, "g0"), p1(ctx, n1 * 4, "p1"), g1(ctx, n1 * 4, "g1");
  auto gr0 = random_floats(n0, rng, 1e-3f), gr1 = random_floats(n1, rng, 10.0f);
  gr0[5] = 0.0f;  // a zero gradient leaves its parameter (and moments) exactly unchanged
  p0.write(std::vector<float>(n0, 0.0f));
  p1.write(std::vector<float>(n1, 0.0f));
  g0.write(gr0);
  g1.write(gr1);
  Adam adam(ctx);  // moments are poisoned (NaN) until the optimizer zeroes them
  adam.add_group({"a", &p0, &g0, n0, 1e-2f, 1});
  adam.add_group({"b", &p1, &g1, n1, 3e-4f, 3});
  CHECK(adam.group_index("b") == 1);
  CHECK(adam.options().eps == 1e-15);
  gpu::Commands cmd(ctx);
  adam.step(cmd);
  cmd.submit();
  CHECK(adam.step_count(0) == 1);
  auto r0 = p0.read<float>(n0), r1 = p1.read<float>(n1);
  double e0 = 0, e1 = 0;
  for (uint32_t i = 0; i < n0; ++i) e0 = std::max(e0, std::abs(r0[i] + 1e-2 * ((gr0[i] > 0) - (gr0[i] < 0))) / 1e-2);
  for (uint32_t i = 0; i < n1; ++i) e1 = std::max(e1, std::abs(r1[i] + 3e-4 * ((gr1[i] > 0) - (gr1[i] < 0))) / 3e-4);
  CHECK(r0[5] == 0.0f);
  CHECK(e0 < 1e-6);
  CHECK(e1 < 1e-6);
  auto m0 = adam.exp_avg(0).read<float>(n0), v0 = adam.exp_avg_sq(0).read<float>(n0);
  CHECK(m0[5] == 0.0f);
  CHECK(v0[5] == 0.0f);
  CHECK(m0[7] == Approx(0.1 * gr0[7]).epsilon(1e-6));
  CHECK(v0[7] == Approx(0.001 * double(gr0[7]) * gr0[7]).epsilon(1e-6));
  test::require_no_validation_messages();
}

TEST_CASE("adam: several steps match the double reference step by step", "[gpu][optim]") {
  auto& ctx = test::gpu_context();
  std::mt19937 rng(2);
  const std::vector<uint32_t> counts = {3 * 23334, 48 * 50};
  const std::vector<float> lrs = {1.6e-4f, 2.5e-3f};
  std::vector<gpu::Buffer> params, grads;
  std::vector<RefAdam> ref(2);
  Adam adam(ctx);
  for (size_t k = 0; k < 2; ++k) {
    params.emplace_back(ctx, counts[k] * 4, "p");
    grads.emplace_back(ctx, counts[k] * 4, "g");
  }
  for (size_t k = 0; k < 2; ++k) {
    auto init = random_floats(counts[k], rng, 1.0f);
    params[k].write(init);
    ref[k].p.assign(init.begin(), init.end());
    ref[k].m.assign(counts[k], 0.0);
    ref[k].v.assign(counts[k], 0.0);
    adam.add_group({k ? "sh" : "means", &params[k], &grads[k], counts[k], lrs[k], k ? 48u : 3u});
  }
  gpu::Commands cmd(ctx);
  double worst_p = 0, worst_mv = 0;
  for (int step = 0; step < 6; ++step) {
    std::vector<std::vector<float>> gs;
    for (size_t k = 0; k < 2; ++k) {
      gs.push_back(random_floats(counts[k], rng, k ? 0.01f : 1.0f));
      grads[k].write(gs[k]);
      // Step by step: the reference starts from the GPU's state (float), so errors don't pile up.
      auto p = params[k].read<float>(counts[k]);
      ref[k].p.assign(p.begin(), p.end());
      if (step > 0) {
        auto m = adam.exp_avg(k).read<float>(counts[k]), v = adam.exp_avg_sq(k).read<float>(counts[k]);
        ref[k].m.assign(m.begin(), m.end());
        ref[k].v.assign(v.begin(), v.end());
      }
      ref[k].step(gs[k], lrs[k]);
    }
    adam.step(cmd);
    cmd.submit();
    for (size_t k = 0; k < 2; ++k) {
      auto p = params[k].read<float>(counts[k]);
      auto m = adam.exp_avg(k).read<float>(counts[k]), v = adam.exp_avg_sq(k).read<float>(counts[k]);
      worst_p = std::max(worst_p, max_rel(p, ref[k].p, ref[k].sp));
      worst_mv = std::max({worst_mv, max_rel(m, ref[k].m, ref[k].sm), max_rel(v, ref[k].v, ref[k].sv)});
    }
  }
  WARN("adam 6 steps: max rel error params " << worst_p << ", moments " << worst_mv);
  CHECK(worst_p < 1e-6);
  CHECK(worst_mv < 1e-6);
  CHECK(adam.step_count(1) == 6);
  test::require_no_validation_messages();
}

// A zero-gradient step of a group that never stepped with a gradient is only counted; once the
// moments are not zero it is an ordinary step. Either way the state equals ordinary steps'.
TEST_CASE("adam: zero-gradient steps equal ordinary steps, counted in the bias correction", "[gpu][optim]") {
  auto& ctx = test::gpu_context();
  std::mt19937 rng(5);
  const uint32_t n = 48 * 40;
  const auto init = random_floats(n, rng, 1.0f);
  gpu::Buffer pa(ctx, n * 4, "pa"), pb(ctx, n * 4, "pb"), grad(ctx, n * 4, "g");
  pa.write(init);
  pb.write(init);
  Adam a(ctx), b(ctx);
  a.add_group({"sh1", &pa, &grad, n, 2.5e-3f, 48});
  b.add_group({"sh1", &pb, &grad, n, 2.5e-3f, 48});
  gpu::Commands cmd(ctx);
  auto same_state = [&] {
    CHECK(a.step_count(0) == b.step_count(0));
    CHECK(pa.read<float>(n) == pb.read<float>(n));
    CHECK(a.exp_avg(0).read<float>(n) == b.exp_avg(0).read<float>(n));
    CHECK(a.exp_avg_sq(0).read<float>(n) == b.exp_avg_sq(0).read<float>(n));
  };
  grad.write(std::vector<float>(n, 0.0f));
  for (int k = 0; k < 3; ++k) {
    a.step_group(cmd, 0);
    b.step_group_zero_grad(cmd, 0);
  }
  cmd.submit();
  same_state();
  CHECK(pb.read<float>(n) == init);
  grad.write(random_floats(n, rng, 0.01f));  // step 4: the first gradient (bias correction at t = 4)
  a.step_group(cmd, 0);
  b.step_group(cmd, 0);
  cmd.submit();
  same_state();
  grad.write(std::vector<float>(n, 0.0f));  // moments no longer zero: an ordinary step moves the parameters
  a.step_group(cmd, 0);
  b.step_group_zero_grad(cmd, 0);
  cmd.submit();
  same_state();
  CHECK(pb.read<float>(n) != init);
  CHECK(b.step_count(0) == 5);
  test::require_no_validation_messages();
}

TEST_CASE("adam: gather (clone/prune) and reset move and zero the state by rows", "[gpu][optim]") {
  auto& ctx = test::gpu_context();
  std::mt19937 rng(3);
  const uint32_t rows = 40, w = 3, n = rows * w;
  gpu::Buffer p(ctx, n * 4, "p"), g(ctx, n * 4, "g");
  auto p_init = random_floats(n, rng, 1.0f);
  p.write(p_init);
  Adam adam(ctx);
  adam.add_group({"means", &p, &g, n, 1e-3f, w});
  gpu::Commands cmd(ctx);
  for (int s = 0; s < 3; ++s) {
    g.write(random_floats(n, rng, 1.0f));
    adam.step(cmd);
    cmd.submit();
  }
  const auto m_old = adam.exp_avg(0).read<float>(n), v_old = adam.exp_avg_sq(0).read<float>(n);
  const auto p_old = p.read<float>(n);

  // Prune rows 3 and 10..19, clone rows 0 and 7 (new state zero, as in 3DGS densification).
  std::vector<uint32_t> index;
  for (uint32_t r = 0; r < rows; ++r)
    if (r != 3 && (r < 10 || r >= 20)) index.push_back(r);
  index.push_back(kAdamNoSource);
  index.push_back(kAdamNoSource);
  const uint32_t new_rows = uint32_t(index.size());
  gpu::Buffer ib(ctx, new_rows * 4, "index");
  ib.write(index);
  std::vector<uint32_t> params_index = index;  // parameters of the clones copy their source
  params_index[new_rows - 2] = 0;
  params_index[new_rows - 1] = 7;
  gpu::Buffer pib(ctx, new_rows * 4, "param_index");
  pib.write(params_index);
  gpu::Buffer p2(ctx, new_rows * w * 4, "p2"), g2(ctx, new_rows * w * 4, "g2");
  Adam::gather_rows(cmd, p, p2, pib, new_rows, w);
  adam.gather(cmd, 0, ib, new_rows);
  adam.set_buffers(0, p2, g2);
  cmd.submit();
  REQUIRE(adam.group(0).count == new_rows * w);
  auto m = adam.exp_avg(0).read<float>(new_rows * w), v = adam.exp_avg_sq(0).read<float>(new_rows * w);
  auto pn = p2.read<float>(new_rows * w);
  bool ok = true;
  for (uint32_t r = 0; r < new_rows; ++r)
    for (uint32_t k = 0; k < w; ++k) {
      const uint32_t i = r * w + k;
      const bool clone = index[r] == kAdamNoSource;
      ok = ok && m[i] == (clone ? 0.0f : m_old[index[r] * w + k]) && v[i] == (clone ? 0.0f : v_old[index[r] * w + k]) &&
           pn[i] == p_old[params_index[r] * w + k];
    }
  CHECK(ok);

  // One more step after the gather matches the reference on the gathered state.
  auto gn = random_floats(new_rows * w, rng, 1.0f);
  g2.write(gn);
  RefAdam ref;
  ref.p.assign(pn.begin(), pn.end());
  ref.m.assign(m.begin(), m.end());
  ref.v.assign(v.begin(), v.end());
  ref.t = adam.step_count(0);
  ref.step(gn, 1e-3);
  adam.step(cmd);
  cmd.submit();
  CHECK(max_rel(p2.read<float>(new_rows * w), ref.p, ref.sp) < 1e-6);

  // Reset by index list (an out-of-range row is ignored) and by mask.
  const auto m_before = adam.exp_avg(0).read<float>(new_rows * w);
  std::vector<uint32_t> list = {2, 5, 1000};
  gpu::Buffer lb(ctx, list.size() * 4, "rows");
  lb.write(list);
  std::vector<uint32_t> mask(new_rows, 0);
  mask[0] = mask[new_rows - 1] = 1;
  gpu::Buffer mb(ctx, new_rows * 4, "mask");
  mb.write(mask);
  adam.reset_rows(cmd, 0, lb, uint32_t(list.size()));
  adam.reset_masked(cmd, 0, mb);
  cmd.submit();
  auto m2 = adam.exp_avg(0).read<float>(new_rows * w), v2 = adam.exp_avg_sq(0).read<float>(new_rows * w);
  ok = true;
  for (uint32_t r = 0; r < new_rows; ++r) {
    const bool zero = r == 2 || r == 5 || mask[r];
    for (uint32_t k = 0; k < w; ++k) {
      const uint32_t i = r * w + k;
      ok = ok && (zero ? (m2[i] == 0.0f && v2[i] == 0.0f) : (m2[i] == m_before[i] && v2[i] != 0.0f));
    }
  }
  CHECK(ok);
  test::require_no_validation_messages();
}

TEST_CASE("adam: exponential learning-rate decay (3DGS means schedule)", "[optim]") {
  ExponentialDecay s{1.6e-4, 1.6e-6, 30000};
  CHECK(s(0) == Approx(1.6e-4));
  CHECK(s(15000) == Approx(1.6e-5));  // geometric midpoint
  CHECK(s(30000) == Approx(1.6e-6));
  CHECK(s(90000) == Approx(1.6e-6));
  ExponentialDecay d{1e-3, 1e-5, 100, 0.01, 10};
  CHECK(d(0) == Approx(1e-5));  // delay_mult * lr_init
  CHECK(d(10) == Approx(1e-3 * std::pow(1e-2, 0.1)));
  CHECK(ExponentialDecay{0, 0, 10}(3) == 0.0);
}
