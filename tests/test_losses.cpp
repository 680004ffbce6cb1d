#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>

#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "loss/image_losses.h"
#include "reference/ssim_reference.h"

using namespace evflow;
namespace ref = evflow::reference;

namespace {

// A smooth random image (a few random sinusoids per channel) in [0, 1], plus a target that is a
// perturbed, shifted copy of it: SSIM well away from 0 and 1, like a render against its photo.
struct ImagePair {
  ImageShape shape;
  ref::ImageDims dims;
  std::vector<float> a, b;
  std::vector<double> ad, bd;
};

ImagePair make_pair(uint32_t c, uint32_t h, uint32_t w, uint32_t seed, double noise = 0.15) {
  ImagePair p;
  p.shape = {c, h, w};
  p.dims = {int(c), int(h), int(w)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> nrm(0.0, 1.0);
  const size_t n = p.shape.count();
  p.a.resize(n), p.b.resize(n);
  for (uint32_t ch = 0; ch < c; ++ch) {
    double fx[3], fy[3], ph[3];
    for (int k = 0; k < 3; ++k) fx[k] = 0.05 + 0.4 * u(rng), fy[k] = 0.05 + 0.4 * u(rng), ph[k] = 6.28 * u(rng);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        double s = 0.5;
        for (int k = 0; k < 3; ++k) s += 0.12 * std::sin(fx[k] * x + fy[k] * y + ph[k]);
        const size_t i = (size_t(ch) * h + y) * w + x;
        const double va = std::clamp(s + 0.05 * nrm(rng), 0.0, 1.0);
        const double vb = std::clamp(s + 0.03 * std::sin(0.3 * x) + noise * nrm(rng), 0.0, 1.0);
        p.a[i] = float(va), p.b[i] = float(vb);
      }
  }
  p.ad.assign(p.a.begin(), p.a.end());
  p.bd.assign(p.b.begin(), p.b.end());
  return p;
}

// Sampled pixels: the four corners, pixels on every border band, and random interior pixels.
std::vector<std::array<int, 3>> sample_pixels(const ref::ImageDims& d, int n_random, uint32_t seed) {
  std::vector<std::array<int, 3>> s;
  std::mt19937 rng(seed);
  for (int c = 0; c < d.channels; ++c) {
    for (int y : {0, 1, 4, 5, d.height - 6, d.height - 1})
      for (int x : {0, 3, 5, d.width / 2, d.width - 5, d.width - 1})
        if (y >= 0 && y < d.height && x >= 0 && x < d.width) s.push_back({c, y, x});
  }
  for (int k = 0; k < n_random; ++k)
    s.push_back({int(rng() % d.channels), int(rng() % d.height), int(rng() % d.width)});
  return s;
}

struct RelStats {
  double median = 0, max = 0;
};

// Relative error |g - r| / max(|r|, floor), floor = 1e-3 * rms(r) (guards near-zero gradients).
RelStats rel_errors(const std::vector<double>& gpu, const std::vector<double>& refv) {
  double rms = 0;
  for (double r : refv) rms += r * r;
  rms = std::sqrt(rms / double(refv.size()));
  std::vector<double> e;
  for (size_t i = 0; i < gpu.size(); ++i)
    e.push_back(std::abs(gpu[i] - refv[i]) / std::max(std::abs(refv[i]), 1e-3 * rms));
  std::sort(e.begin(), e.end());
  return {e[e.size() / 2], e.back()};
}

struct GpuImages {
  gpu::Buffer a, b, grad;
  GpuImages(gpu::Context& ctx, const ImagePair& p)
      : a(ctx, p.shape.count() * 4, "pred"),
        b(ctx, p.shape.count() * 4, "target"),
        grad(ctx, p.shape.count() * 4, "grad") {
    a.write(p.a);
    b.write(p.b);
  }
};

}  // namespace

TEST_CASE("loss: SSIM forward matches the double reference (map and mean, borders)", "[gpu][loss]") {
  auto& ctx = test::gpu_context();
  for (auto [c, h, w, noise] : std::vector<std::tuple<uint32_t, uint32_t, uint32_t, double>>{
           {3, 61, 47, 0.15}, {1, 7, 13, 0.3}, {2, 12, 11, 0.0}, {3, 33, 5, 1.0}}) {
    auto p = make_pair(c, h, w, 1000 + h, noise);
    GpuImages g(ctx, p);
    ImageMetrics metrics(ctx, p.shape);
    gpu::Commands cmd(ctx);
    metrics.record(cmd, g.a, g.b, /*write_map=*/true);
    cmd.submit();
    const auto map = metrics.ssim_map_buffer().read<float>(p.shape.count(), metrics.ssim_map_offset_bytes());
    const auto refmap = ref::ssim_map(p.ad, p.bd, p.dims);
    double max_map_err = 0;
    for (size_t i = 0; i < map.size(); ++i) max_map_err = std::max(max_map_err, std::abs(double(map[i]) - refmap[i]));
    // The separable reference agrees with the direct 2D window at a few pixels (incl. corners).
    for (auto [cc, yy, xx] : sample_pixels(p.dims, 5, 7))
      REQUIRE(std::abs(ref::ssim_pixel(p.ad, p.bd, p.dims, cc, yy, xx) - refmap[p.dims.index(cc, yy, xx)]) < 1e-12);
    const auto v = metrics.read();
    const double ref_ssim = ref::ssim_mean(p.ad, p.bd, p.dims);
    INFO(c << "x" << h << "x" << w << ": SSIM " << v.ssim << " ref " << ref_ssim << ", max map error " << max_map_err);
    CHECK(std::abs(v.ssim - ref_ssim) < 1e-5);
    CHECK(max_map_err < 2e-4);
    if (h == 61)
      WARN("SSIM 3x61x47: mean error " << std::abs(v.ssim - ref_ssim) << ", max per-pixel error " << max_map_err);
  }
  test::require_no_validation_messages();
}

TEST_CASE("loss: SSIM and L1 gradients match finite differences of the reference", "[gpu][loss]") {
  auto& ctx = test::gpu_context();
  auto p = make_pair(3, 61, 47, 42);
  GpuImages g(ctx, p);
  SsimLoss ssim(ctx, p.shape, 1.0f);
  L1Loss l1(ctx, p.shape, 1.0f);
  gpu::Buffer grad_l1(ctx, p.shape.count() * 4, "grad_l1");
  gpu::Commands cmd(ctx);
  ssim.record(cmd, g.a, g.b, g.grad, false);  // grad of (1 - SSIM), weight 1
  l1.record(cmd, g.a, g.b, grad_l1, false);
  cmd.submit();
  const auto gs = g.grad.read<float>(p.shape.count());
  const auto gl = grad_l1.read<float>(p.shape.count());
  const auto sv = ssim.values();
  const double ref_ssim = ref::ssim_mean(p.ad, p.bd, p.dims);
  CHECK(std::abs(sv[1] - ref_ssim) < 1e-5);
  CHECK(std::abs(sv[0] - (1.0 - ref_ssim)) < 1e-5);
  CHECK(std::abs(l1.value() - ref::l1_mean(p.ad, p.bd)) < 1e-6);

  std::vector<double> g_ssim, r_ssim, g_l1, r_l1;
  for (auto [c, y, x] : sample_pixels(p.dims, 150, 5)) {
    const size_t i = p.dims.index(c, y, x);
    g_ssim.push_back(-double(gs[i]));  // d SSIM / dA = -d(1 - SSIM)/dA
    r_ssim.push_back(ref::fd_ssim_mean(p.ad, p.bd, p.dims, c, y, x));
    g_l1.push_back(gl[i]);
    r_l1.push_back(ref::fd_l1_mean(p.ad, p.bd, p.dims, c, y, x));
  }
  const auto es = rel_errors(g_ssim, r_ssim), el = rel_errors(g_l1, r_l1);
  WARN("SSIM gradient vs FD over " << g_ssim.size() << " pixels: median rel " << es.median << ", max rel " << es.max
                                   << "; L1: median " << el.median << ", max " << el.max);
  CHECK(es.median < 1e-3);
  CHECK(es.max < 5e-2);
  CHECK(el.median < 1e-3);
  CHECK(el.max < 1e-3);
  test::require_no_validation_messages();
}

TEST_CASE("loss: blended L1 + SSIM value and gradient, terms accumulate into one gradient", "[gpu][loss]") {
  auto& ctx = test::gpu_context();
  auto p = make_pair(3, 29, 37, 9);
  GpuImages g(ctx, p);
  const float weight = 1.7f;
  BlendLoss blend(ctx, p.shape);  // lambda 0.2
  REQUIRE(blend.lambda() == Approx(0.2f));
  gpu::Commands cmd(ctx);
  blend.record(cmd, g.a, g.b, g.grad, weight, false);
  cmd.submit();
  const auto gb = g.grad.read<float>(p.shape.count());
  const auto v = blend.values();
  const double lam = 0.2;
  CHECK(std::abs(v[0] - ref::blend_loss(p.ad, p.bd, p.dims, lam)) < 1e-5);
  CHECK(std::abs(v[1] - ref::l1_mean(p.ad, p.bd)) < 1e-6);
  CHECK(std::abs(v[2] - ref::ssim_mean(p.ad, p.bd, p.dims)) < 1e-5);

  std::vector<double> gg, rr;
  for (auto [c, y, x] : sample_pixels(p.dims, 100, 6)) {
    gg.push_back(gb[p.dims.index(c, y, x)] / weight);
    rr.push_back(ref::fd_blend_loss(p.ad, p.bd, p.dims, lam, c, y, x));
  }
  const auto e = rel_errors(gg, rr);
  WARN("blend gradient vs FD: median rel " << e.median << ", max rel " << e.max);
  CHECK(e.median < 1e-3);
  CHECK(e.max < 5e-2);

  // The same gradient from separate terms added into one buffer (L1 overwrites, SSIM adds), on
  // top of a prior gradient (accumulate), into a shared value buffer.
  L1Loss l1(ctx, p.shape, float(weight * (1 - lam)));
  SsimLoss ssim(ctx, p.shape, float(weight * lam));
  gpu::Buffer vals(ctx, 8 * 4, "loss_values");
  l1.set_value_slot(vals, 0);
  ssim.set_value_slot(vals, 1);
  gpu::Buffer sum(ctx, p.shape.count() * 4, "sum");
  std::vector<float> prior(p.shape.count());
  for (size_t i = 0; i < prior.size(); ++i) prior[i] = 1e-3f * float(i % 17);
  gpu::Buffer acc(ctx, p.shape.count() * 4, "acc");
  acc.write(prior);
  l1.record(cmd, g.a, g.b, sum, false);
  ssim.record(cmd, g.a, g.b, sum, true);
  l1.record(cmd, g.a, g.b, acc, true);
  ssim.record(cmd, g.a, g.b, acc, true);
  cmd.submit();
  const auto gs = sum.read<float>(p.shape.count());
  const auto ga = acc.read<float>(p.shape.count());
  double max_diff = 0, max_acc = 0, scale = 0;
  for (size_t i = 0; i < gs.size(); ++i) {
    scale = std::max(scale, double(std::abs(gb[i])));
    max_diff = std::max(max_diff, double(std::abs(gs[i] - gb[i])));
    max_acc = std::max(max_acc, double(std::abs(ga[i] - (prior[i] + gb[i]))));
  }
  CHECK(max_diff <= 1e-5 * scale);
  CHECK(max_acc <= 1e-6);
  const auto all = vals.read<float>(3);  // one download: [L1, 1 - SSIM, SSIM]
  CHECK((1 - lam) * all[0] + lam * all[1] == Approx(v[0]).epsilon(1e-5));
  CHECK(all[2] == Approx(v[2]).epsilon(1e-6));
  test::require_no_validation_messages();
}

TEST_CASE("loss: PSNR and SSIM metrics, reductions are deterministic", "[gpu][loss]") {
  auto& ctx = test::gpu_context();
  auto p = make_pair(3, 64, 80, 77, 0.05);
  GpuImages g(ctx, p);
  ImageMetrics metrics(ctx, p.shape);
  gpu::Commands cmd(ctx);
  metrics.record(cmd, g.a, g.b);
  cmd.submit();
  const auto v1 = metrics.read();
  metrics.record(cmd, g.a, g.b);
  cmd.submit();
  const auto v2 = metrics.read();
  INFO("PSNR " << v1.psnr << " ref " << ref::psnr(p.ad, p.bd));
  CHECK(std::abs(v1.psnr - ref::psnr(p.ad, p.bd)) < 1e-4);
  CHECK(std::abs(v1.mse - ref::mse(p.ad, p.bd)) < 1e-6 * ref::mse(p.ad, p.bd) + 1e-9);
  CHECK(std::abs(v1.ssim - ref::ssim_mean(p.ad, p.bd, p.dims)) < 1e-5);
  CHECK(std::memcmp(&v1, &v2, sizeof v1) == 0);
  // Identical images: SSIM 1, PSNR infinite.
  metrics.record(cmd, g.a, g.a);
  cmd.submit();
  const auto same = metrics.read();
  CHECK(same.ssim == Approx(1.0).epsilon(1e-6));
  CHECK(same.mse == 0.0);
  CHECK(std::isinf(same.psnr));
  test::require_no_validation_messages();
}

TEST_CASE("loss: SSIM forward+backward timing at 3x260x346", "[.][loss-bench]") {
  auto& ctx = test::gpu_context();
  auto p = make_pair(3, 260, 346, 3);
  GpuImages g(ctx, p);
  BlendLoss blend(ctx, p.shape);
  gpu::Commands cmd(ctx);
  std::vector<double> wall, gpu_ms;
  for (int it = 0; it < 12; ++it) {
    blend.record(cmd, g.a, g.b, g.grad, false);
    cmd.mark("blend");
    auto t0 = std::chrono::steady_clock::now();
    cmd.submit();
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!cmd.stage_ms().empty()) gpu_ms.push_back(cmd.stage_ms()[0].second);
    (void)blend.value();
  }
  std::sort(wall.begin() + 2, wall.end());
  std::sort(gpu_ms.begin(), gpu_ms.end());
  WARN(ctx.caps().name << ": L1+SSIM forward+backward 3x260x346: submit wall median " << wall[2 + (wall.size() - 2) / 2]
                       << " ms, GPU timestamps median " << (gpu_ms.empty() ? -1.0 : gpu_ms[gpu_ms.size() / 2])
                       << " ms");
  test::require_no_validation_messages();
}
