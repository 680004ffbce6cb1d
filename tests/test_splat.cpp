// GPU rasterizer vs the double-precision CPU reference (tests/reference): forward within 1e-4,
// every gradient (pose included) against central finite differences of the reference.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "gpu_fixture.h"
#include "reference/random_scene.h"
#include "reference/splat_reference.h"
#include "splat/rasterizer.h"

using namespace evflow;
using reference::Param;

namespace {

struct Scene {
  GaussianCloud cloud;
  Camera cam;
  RenderSettings settings;
};

Scene make_scene(uint64_t seed, size_t n, int degree, uint32_t w, uint32_t h, bool aa) {
  Scene s;
  s.cam = reference::test_camera(w, h);
  s.cloud = reference::random_scene(seed, n, degree, s.cam);
  s.settings.antialiased = aa;
  s.settings.background = {0.2f, 0.5f, 0.9f};
  return s;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Of several finite differences at different steps, the mean of the two that agree best: a step
// that straddles a discontinuity gives a value ~jump/h that agrees with none of the others.
double consensus(const std::vector<double>& v) {
  double best = 1e300, out = v[0];
  for (size_t a = 0; a < v.size(); ++a)
    for (size_t b = a + 1; b < v.size(); ++b) {
      double d = std::abs(v[a] - v[b]) / std::max({std::abs(v[a]), std::abs(v[b]), 1e-12});
      if (d < best) {
        best = d;
        out = 0.5 * (v[a] + v[b]);
      }
    }
  return out;
}

// A 64x48 random scene uploaded, gradient buffers, and random image gradients (v_rgb, v_alpha).
struct BackwardSetup {
  BackwardSetup(gpu::Context& ctx, uint64_t seed)
      : s(make_scene(seed, 400, 1, 64, 48, false)),
        params(ctx, s.cloud.size(), 1, "p_"),
        grads(ctx, s.cloud.size(), 1, "v_"),
        vr(ctx, 64 * 48 * 12, "v_rgb"),
        va(ctx, 64 * 48 * 4, "v_alpha") {
    params.upload(s.cloud);
    vr.write(reference::random_weights(seed * 2, 3 * 64 * 48));
    va.write(reference::random_weights(seed * 2 + 1, 64 * 48));
  }
  Scene s;
  GaussianBuffers params, grads;
  gpu::Buffer vr, va;
};

}  // namespace

TEST_CASE("splat forward matches the double-precision reference", "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  // Antialiased or not at the cloud's SH degree; and one render at an active degree below it.
  for (int variant : {0, 1, 2}) {
    const bool aa = variant == 1;
    Scene s = make_scene(variant == 0 ? 5 : variant == 1 ? 7 : 9, 2000, 3, 160, 120, aa);
    if (variant == 2) s.settings.sh_degree = 1;
    GaussianBuffers params(ctx, s.cloud.size(), s.cloud.sh_degree, "p_");
    params.upload(s.cloud);
    Rasterizer r(ctx);
    RenderState rs(ctx);
    r.forward(params, s.cam, s.settings, rs);
    auto ref = reference::render(s.cloud, s.cam, s.settings);
    const size_t hw = size_t(s.cam.width) * s.cam.height;
    auto rgb = rs.outputs().rgb.read<float>(3 * hw);
    auto alpha = rs.outputs().alpha.read<float>(hw);
    double max_rgb = 0, max_alpha = 0;
    for (size_t i = 0; i < 3 * hw; ++i) max_rgb = std::max(max_rgb, std::abs(rgb[i] - ref.rgb[i]));
    for (size_t i = 0; i < hw; ++i) max_alpha = std::max(max_alpha, std::abs(alpha[i] - ref.alpha[i]));
    std::printf(
        "forward (antialiased %d, SH degree %d): %u intersections, max |rgb - ref| %.3g, max |alpha - ref| %.3g\n", aa,
        s.settings.sh_degree, rs.num_intersections(), max_rgb, max_alpha);
    REQUIRE(rs.num_intersections() > 2000);
    // GPUs compute exp and division to the few ulps Vulkan allows, not correctly rounded.
    const double tol = ctx.caps().cpu_driver ? 1e-4 : 1e-3;
    REQUIRE(max_rgb <= tol);
    REQUIRE(max_alpha <= tol);
  }
  test::require_no_validation_messages();
}

static void check_gradients(gpu::Context& ctx, const Scene& s, size_t sampled_gaussians, uint64_t seed) {
  const size_t hw = size_t(s.cam.width) * s.cam.height;
  auto v_rgb = reference::random_weights(seed, 3 * hw);
  auto v_alpha = reference::random_weights(seed + 1, hw);
  GaussianBuffers params(ctx, s.cloud.size(), s.cloud.sh_degree, "p_");
  GaussianBuffers grads(ctx, s.cloud.size(), s.cloud.sh_degree, "v_");
  params.upload(s.cloud);
  gpu::Buffer b_vrgb(ctx, 3 * hw * 4, "v_rgb"), b_valpha(ctx, hw * 4, "v_alpha");
  b_vrgb.write(v_rgb);
  b_valpha.write(v_alpha);
  Rasterizer r(ctx);
  RenderState rs(ctx);
  r.forward(params, s.cam, s.settings, rs);
  r.backward(rs, params, b_vrgb, b_valpha, grads);
  GaussianCloud g = grads.download();
  auto pose = r.pose_gradient();
  reference::FiniteDifferences fd(s.cloud, s.cam, s.settings, v_rgb, v_alpha);

  // The rendered image is discontinuous where a Gaussian's alpha crosses 1/255 or a pixel's
  // transmittance stop moves; like every 3DGS gradient, ours is the gradient of the smooth part.
  // A central difference over a step h straddles such a jump with probability ~h, and then is
  // off by ~jump/h: small steps (exact enough in double precision) keep those rare.
  const double h = 1e-6;
  // Gaussians that are visible (non-zero gradient somewhere) get sampled.
  std::vector<size_t> ids(s.cloud.size());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = i;
  std::mt19937_64 rng(seed);
  std::shuffle(ids.begin(), ids.end(), rng);
  ids.resize(std::min(sampled_gaussians, ids.size()));
  struct Kind {
    Param p;
    const char* name;
    const std::vector<float>* v;
    int comps;
  };
  const int K = s.cloud.coeffs();
  std::vector<Kind> kinds = {{Param::Mean, "means", &g.means, 3},
                             {Param::LogScale, "log_scales", &g.log_scales, 3},
                             {Param::Quat, "quats", &g.quats, 4},
                             {Param::OpacityLogit, "opacity_logits", &g.opacity_logits, 1},
                             {Param::Sh, "sh", &g.sh, K * 3}};
  for (auto& kind : kinds) {
    std::vector<double> rel;
    size_t zero_both = 0;
    for (size_t id : ids)
      for (int c = 0; c < kind.comps; ++c) {
        double gpu = (*kind.v)[id * kind.comps + c];
        double ref = fd.param(kind.p, id, c, h);
        if (std::abs(gpu - ref) > 1e-3 * std::max(std::abs(gpu), std::abs(ref)))  // a jump? re-check with consensus
          ref = consensus({ref, fd.param(kind.p, id, c, 1e-5), fd.param(kind.p, id, c, 3e-6),
                           fd.param(kind.p, id, c, 3e-7), fd.param(kind.p, id, c, 1e-7)});
        double scale = std::max(std::abs(gpu), std::abs(ref));
        if (scale < 1e-7) {
          ++zero_both;
          continue;
        }
        rel.push_back(std::abs(gpu - ref) / scale);
      }
    double med = median(rel), mx = rel.empty() ? 0 : *std::max_element(rel.begin(), rel.end());
    size_t above = std::count_if(rel.begin(), rel.end(), [](double e) { return e > 1e-2; });
    std::printf("gradient %-15s %5zu compared (%zu both ~0): median rel. error %.2e, max %.2e, %zu above 1e-2\n",
                kind.name, rel.size(), zero_both, med, mx, above);
    INFO(kind.name);
    REQUIRE(rel.size() > ids.size() / 4);
    REQUIRE(med < 1e-3);
    REQUIRE(above * 100 <= rel.size());  // outliers: parameters sitting on a discontinuity
  }
  // Every Gaussian moves with the camera, so some pixel flips at the 1/255 threshold even for
  // small steps; take, per component, the two step sizes that agree best (a jump shows up as a
  // value that scales with 1/h and agrees with none of the others).
  std::vector<std::array<double, 6>> trials;
  for (double step : {3e-9, 1e-9, 3e-10, 1e-10}) trials.push_back(fd.pose(step));
  std::array<double, 6> fpose{};
  for (int i = 0; i < 6; ++i) fpose[i] = consensus({trials[0][i], trials[1][i], trials[2][i], trials[3][i]});
  std::vector<double> rel;
  for (int i = 0; i < 6; ++i) {
    double e = std::abs(pose[i] - fpose[i]) / std::max({std::abs(double(pose[i])), std::abs(fpose[i]), 1e-9});
    rel.push_back(e);
    std::printf("pose[%d]: gpu %.6g  fd %.6g  rel. error %.2e\n", i, pose[i], fpose[i], e);
  }
  REQUIRE(median(rel) < 1e-3);
  REQUIRE(*std::max_element(rel.begin(), rel.end()) < 1e-2);
}

TEST_CASE("splat gradients match finite differences of the reference", "[gpu][splat][gradient]") {
  auto& ctx = test::gpu_context();
  SECTION("SH degree 3") { check_gradients(ctx, make_scene(21, 2000, 3, 160, 120, false), 250, 3); }
  SECTION("antialiased, SH degree 1") { check_gradients(ctx, make_scene(22, 2000, 1, 176, 128, true), 250, 4); }
  test::require_no_validation_messages();
}

TEST_CASE("splat kernels: block and per-pixel, compare-and-swap and subgroup-reduction paths agree", "[gpu][splat]") {
  Scene s = make_scene(31, 600, 2, 96, 80, false);
  struct Result {
    GaussianCloud grads;
    std::vector<float> rgb, alpha;
  };
  auto run = [&](gpu::Context& ctx, const RasterKernels& kernels) {
    GaussianBuffers params(ctx, s.cloud.size(), 2, "p_"), grads(ctx, s.cloud.size(), 2, "v_");
    params.upload(s.cloud);
    const size_t hw = 96 * 80;
    gpu::Buffer vr(ctx, hw * 12, "v_rgb"), va(ctx, hw * 4, "v_alpha");
    vr.write(reference::random_weights(1, 3 * hw));
    va.write(reference::random_weights(2, hw));
    Rasterizer r(ctx, kernels);
    RenderState rs(ctx);
    r.forward(params, s.cam, s.settings, rs);
    r.backward(rs, params, vr, va, grads);
    return Result{grads.download(), rs.outputs().rgb.read<float>(3 * hw), rs.outputs().alpha.read<float>(hw)};
  };
  // The block kernels take exp(power) of a block's pixels as products of factors (block_exp),
  // which round differently from one exp a pixel: colours agree within 3e-6.
  auto same = [](const Result& a, const Result& b) {
    for (size_t i = 0; i < a.rgb.size(); ++i) REQUIRE(a.rgb[i] == Approx(b.rgb[i]).margin(3e-6));
    for (size_t i = 0; i < a.alpha.size(); ++i) REQUIRE(a.alpha[i] == Approx(b.alpha[i]).margin(3e-6));
    // Each gradient a sum over pixels, added in another order by each path, with those
    // exponentials: within 1e-3 of itself, or on GPUs (whose adds come in any order) of its
    // array's largest magnitude.
    auto near = [](const std::vector<float>& x, const std::vector<float>& y) {
      REQUIRE(x.size() == y.size());
      if (!test::bit_reproducible()) {
        REQUIRE(test::same_values(x, y));
        return;
      }
      for (size_t i = 0; i < x.size(); ++i) REQUIRE(x[i] == Approx(y[i]).margin(1e-6).epsilon(1e-3));
    };
    near(a.grads.means, b.grads.means);
    near(a.grads.quats, b.grads.quats);
    near(a.grads.sh, b.grads.sh);
  };
  // The device's default kernels (CPU drivers: several pixels per invocation).
  auto& ctx = test::gpu_context();
  const RasterKernels device = RasterKernels::for_context(ctx);
  auto a = run(ctx, device);
  // Without shared float atomics: the compare-and-swap build.
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  o.validation = true;
  o.poison = true;
  o.force_cas = true;
  gpu::Context cas_ctx(o);
  REQUIRE_FALSE(cas_ctx.caps().shared_float_atomic_add);
  same(a, run(cas_ctx, device));
  REQUIRE(cas_ctx.take_validation_messages().empty());
  // Both compositing kernels, whichever the device picks by default.
  for (bool block : {false, true}) {
    INFO((block ? "block" : "pixel"));
    RasterKernels k = device;
    k.block = block;
    same(a, run(ctx, k));
    same(a, run(cas_ctx, k));
    REQUIRE(cas_ctx.take_validation_messages().empty());
  }
  // And both reductions of the per-pixel backward: subgroupAdd first (GPUs) and per-lane adds
  // (CPU drivers).
  for (bool subgroup : {false, true}) {
    INFO("subgroup_reduce " << subgroup);
    same(a, run(ctx, RasterKernels{false, subgroup}));
  }
  test::require_no_validation_messages();
}

// Gaussians one behind the other along the viewing ray, farthest first by index, their depths a
// few ulps apart: every sort key quantises them alike, so only the depths themselves can order
// them. A pair at the centre, six to the right (a run longer than two).
TEST_CASE("splat depth order: Gaussians whose depths share a sort key blend in the order of their depths",
          "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  const Camera cam = Camera::look_at(160, 120, 60.0, {0, 0, 0}, {0, 0, 1}, {0, 1, 0});
  GaussianCloud cloud;
  const int groups[2] = {2, 6};
  cloud.resize(groups[0] + groups[1], 0);
  size_t g = 0;
  for (int group = 0; group < 2; ++group)
    for (int k = 0; k < groups[group]; ++k, ++g) {
      const float z = 3.0f + 4.8e-7f * float(groups[group] - 1 - k);  // two ulps apart at 3
      const float mean[3] = {group == 0 ? 0.0f : 0.6f, 0.05f * float(group), z};
      for (int c = 0; c < 3; ++c) {
        cloud.means[g * 3 + c] = mean[c];
        cloud.log_scales[g * 3 + c] = std::log(0.25f);
        // Colours apart from each other, so that any two in the wrong order show.
        const double rgb = c == 0 ? 0.1 + 0.8 * (k % 2) : c == 1 ? 0.15 * k : 0.9 - 0.12 * k;
        cloud.sh[g * 3 + c] = float((rgb - 0.5) / reference::kShC0);
      }
      cloud.quats[g * 4] = 1.0f;
      for (int c = 1; c < 4; ++c) cloud.quats[g * 4 + c] = 0.0f;
      cloud.opacity_logits[g] = 0.4f;
    }
  RenderSettings settings;
  settings.background = {0.2f, 0.5f, 0.9f};
  auto ref = reference::render(cloud, cam, settings);
  GaussianBuffers params(ctx, cloud.size(), 0, "p_");
  params.upload(cloud);
  const size_t hw = size_t(cam.width) * cam.height;
  for (bool block : {false, true}) {
    INFO((block ? "block" : "pixel"));
    RasterKernels k = RasterKernels::for_context(ctx);
    k.block = block;
    Rasterizer r(ctx, k);
    RenderState rs(ctx);
    r.forward(params, cam, settings, rs);
    auto rgb = rs.outputs().rgb.read<float>(3 * hw);
    double worst = 0;
    for (size_t i = 0; i < 3 * hw; ++i) worst = std::max(worst, std::abs(double(rgb[i]) - ref.rgb[i]));
    std::printf("depth order (%s kernels): %u intersections, max |rgb - ref| %.3g\n", block ? "block" : "pixel",
                rs.num_intersections(), worst);
    REQUIRE(rs.num_intersections() > 8);
    REQUIRE(worst <= (ctx.caps().cpu_driver ? 1e-4 : 1e-3));
  }
  test::require_no_validation_messages();
}

TEST_CASE("splat render without depth: the same image, state and gradients, the depth plane untouched",
          "[gpu][splat]") {
  Scene s = make_scene(37, 600, 1, 96, 80, false);
  const size_t hw = 96 * 80;
  auto& ctx = test::gpu_context();
  struct Result {
    std::vector<float> rgb, alpha, depth, depth_before;
    GaussianCloud grads;
  };
  // Each compositing kernel; the block forward has a build of its own without depth.
  for (bool block : {false, true}) {
    INFO((block ? "block" : "pixel"));
    RasterKernels k = RasterKernels::for_context(ctx);
    k.block = block;
    auto run = [&](bool depth) {
      GaussianBuffers params(ctx, s.cloud.size(), 1, "p_"), grads(ctx, s.cloud.size(), 1, "v_");
      params.upload(s.cloud);
      gpu::Buffer vr(ctx, hw * 12, "v_rgb"), va(ctx, hw * 4, "v_alpha");
      vr.write(reference::random_weights(3, 3 * hw));
      va.write(reference::random_weights(4, hw));
      Rasterizer r(ctx, k);
      RenderState rs(ctx);
      RenderSettings settings = s.settings;
      settings.depth = depth;
      // The state's depth plane first holds the depth of the camera 0.3 further back.
      RenderSettings first = s.settings;
      first.depth = true;
      r.forward(params, s.cam.perturbed({0, 0, -0.3, 0, 0, 0}), first, rs);
      const std::vector<float> before = rs.outputs().depth.read<float>(hw);
      r.forward(params, s.cam, settings, rs);
      r.backward(rs, params, vr, va, grads);
      return Result{rs.outputs().rgb.read<float>(3 * hw), rs.outputs().alpha.read<float>(hw),
                    rs.outputs().depth.read<float>(hw), before, grads.download()};
    };
    const Result with = run(true), without = run(false);
    REQUIRE(with.rgb == without.rgb);
    REQUIRE(with.alpha == without.alpha);
    REQUIRE(with.grads.means == without.grads.means);
    REQUIRE(with.grads.quats == without.grads.quats);
    REQUIRE(with.grads.opacity_logits == without.grads.opacity_logits);
    REQUIRE(with.grads.sh == without.grads.sh);
    size_t covered = 0;
    for (size_t i = 0; i < hw; ++i) covered += with.alpha[i] > 0.1f && with.depth[i] != with.depth_before[i];
    CHECK(covered > hw / 4);  // the two cameras' depths differ
    // The block forward's build without depth leaves the plane as it was; the per-pixel kernel
    // writes it anyway.
    CHECK(without.depth == (block ? without.depth_before : with.depth));
  }
  test::require_no_validation_messages();
}

TEST_CASE("splat backward with accumulate adds to the gradient buffers", "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  BackwardSetup setup(ctx, 41);
  Scene& s = setup.s;
  GaussianBuffers &params = setup.params, &grads = setup.grads;
  gpu::Buffer &vr = setup.vr, &va = setup.va;
  Rasterizer r(ctx);
  RenderState rs(ctx);
  r.forward(params, s.cam, s.settings, rs);
  r.backward(rs, params, vr, va, grads);
  GaussianCloud once = grads.download();
  auto norm_once = r.grad2d_norm().read<float>(s.cloud.size());
  r.backward(rs, params, vr, va, grads, true);
  GaussianCloud twice = grads.download();
  auto norm_twice = r.grad2d_norm().read<float>(s.cloud.size());
  auto doubled = [](std::vector<float> v) {
    for (float& x : v) x *= 2.0f;
    return v;
  };
  REQUIRE(test::same_values(twice.means, doubled(once.means)));
  REQUIRE(test::same_values(twice.sh, doubled(once.sh)));
  REQUIRE(test::same_values(norm_twice, doubled(norm_once)));
  test::require_no_validation_messages();
}

TEST_CASE("splat backward with accumulate below the buffers' SH degree adds zero to the higher bands", "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  Scene s = make_scene(47, 400, 3, 64, 48, false);
  s.settings.sh_degree = 1;  // active bands 0 and 1: coefficients 0..3
  GaussianBuffers params(ctx, s.cloud.size(), 3, "p_"), grads(ctx, s.cloud.size(), 3, "v_");
  params.upload(s.cloud);
  gpu::Buffer vr(ctx, 64 * 48 * 12, "v_rgb"), va(ctx, 64 * 48 * 4, "v_alpha");
  vr.write(reference::random_weights(94, 3 * 64 * 48));
  va.write(reference::random_weights(95, 64 * 48));
  Rasterizer r(ctx);
  RenderState rs(ctx);
  r.forward(params, s.cam, s.settings, rs);
  r.backward(rs, params, vr, va, grads);
  GaussianCloud once = grads.download();
  const size_t coeffs = 16, active = 4;
  size_t nonzero_active = 0;
  for (size_t i = 0; i < once.sh.size(); ++i) {
    if ((i / 3) % coeffs >= active) REQUIRE(once.sh[i] == 0.0f);
    nonzero_active += (i / 3) % coeffs < active && once.sh[i] != 0.0f;
  }
  REQUIRE(nonzero_active > 100);
  // Whatever the higher bands hold stays; the active bands and the rest double.
  GaussianCloud marked = once;
  for (size_t i = 0; i < marked.sh.size(); ++i)
    if ((i / 3) % coeffs >= active) marked.sh[i] = 7.0f;
  grads.upload(marked);
  r.backward(rs, params, vr, va, grads, true);
  GaussianCloud twice = grads.download();
  for (size_t i = 0; i < twice.sh.size(); ++i) {
    INFO("sh value " << i);
    REQUIRE(twice.sh[i] == ((i / 3) % coeffs >= active ? 7.0f : 2.0f * once.sh[i]));
  }
  for (size_t i = 0; i < twice.means.size(); ++i) REQUIRE(twice.means[i] == 2.0f * once.means[i]);
  test::require_no_validation_messages();
}

TEST_CASE("splat render states kept side by side: each backward equals a fresh render's, norms added", "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  BackwardSetup setup(ctx, 43);
  Scene& s = setup.s;
  GaussianBuffers &params = setup.params, &grads = setup.grads;
  gpu::Buffer &vr = setup.vr, &va = setup.va;
  Camera moved = s.cam;
  moved.t[0] += 0.05;  // a second pose, as a virtual frame along an exposure
  // Reference: each pose rendered right before its backward, one state.
  Rasterizer one(ctx);
  RenderState only(ctx);
  std::vector<GaussianCloud> ref;
  std::vector<std::array<float, 6>> ref_pose;
  for (const Camera& c : {s.cam, moved}) {
    one.forward(params, c, s.settings, only);
    one.backward(only, params, vr, va, grads);
    ref.push_back(grads.download());
    ref_pose.push_back(one.pose_gradient());
  }
  one.forward(params, s.cam, s.settings, only);
  one.backward(only, params, vr, va, grads);
  one.forward(params, moved, s.settings, only);
  one.backward(only, params, vr, va, grads, true);
  auto ref_norm_sum = one.grad2d_norm().read<float>(s.cloud.size());
  // Both forwards first into their own states, then the backwards in reverse order through one
  // rasterizer (its scratch shared); the second adds its screen-gradient norms.
  auto same_pose = [](const std::array<float, 6>& x, const std::array<float, 6>& y) {
    return test::same_values({x.begin(), x.end()}, {y.begin(), y.end()});
  };
  Rasterizer r(ctx);
  RenderState a = r.forward(params, s.cam, s.settings);
  RenderState b = r.forward(params, moved, s.settings);
  r.backward(b, params, vr, va, grads);
  REQUIRE(test::same_values(grads.download().means, ref[1].means));
  REQUIRE(test::same_values(grads.download().sh, ref[1].sh));
  REQUIRE(same_pose(r.pose_gradient(), ref_pose[1]));
  r.backward(a, params, vr, va, grads);
  const GaussianCloud ga = grads.download();
  REQUIRE(test::same_values(ga.means, ref[0].means));
  REQUIRE(test::same_values(ga.log_scales, ref[0].log_scales));
  REQUIRE(test::same_values(ga.opacity_logits, ref[0].opacity_logits));
  REQUIRE(same_pose(r.pose_gradient(), ref_pose[0]));
  r.backward(b, params, vr, va, grads, true);
  REQUIRE(test::same_values(r.grad2d_norm().read<float>(s.cloud.size()), ref_norm_sum));
  test::require_no_validation_messages();
}

TEST_CASE("splat batch: an exposure's frames rendered and differentiated in one submit equal one at a time",
          "[gpu][splat]") {
  auto& ctx = test::gpu_context();
  const uint32_t w = 128, h = 96;
  Scene s = make_scene(47, 3000, 1, w, h, false);
  GaussianBuffers params(ctx, s.cloud.size(), 1, "p_"), grads(ctx, s.cloud.size(), 1, "v_");
  params.upload(s.cloud);
  gpu::Buffer vr(ctx, w * h * 12, "v_rgb"), va(ctx, w * h * 4, "v_alpha");
  vr.write(reference::random_weights(94, 3 * w * h));
  va.write(reference::random_weights(95, w * h));
  // Frames ever nearer the scene, so each sorts more intersections than the last: the sort's
  // scratch must be grown for the largest before any frame is recorded.
  std::vector<Camera> cams;
  for (int i = 0; i < 3; ++i) {
    Camera c = s.cam;
    c.t[2] += 3.0f - 1.5f * float(i);
    cams.push_back(c);
  }
  std::vector<std::vector<float>> ref_rgb;
  std::vector<GaussianCloud> ref_grads;
  std::vector<std::array<float, 6>> ref_pose;
  std::vector<uint32_t> isects;
  Rasterizer one(ctx);
  std::vector<RenderState> mine;
  for (const Camera& c : cams) {
    mine.push_back(one.forward(params, c, s.settings));
    ref_rgb.push_back(mine.back().outputs().rgb.read<float>(3 * w * h));
    isects.push_back(mine.back().num_intersections());
  }
  std::printf("splat batch: %u, %u and %u intersections\n", isects[0], isects[1], isects[2]);
  REQUIRE(isects[0] < isects[1]);
  REQUIRE(isects[1] < isects[2]);
  for (size_t i = 0; i < cams.size(); ++i) {
    one.backward(mine[i], params, vr, va, grads, i > 0);
    ref_pose.push_back(one.pose_gradient());
  }
  const GaussianCloud ref = grads.download();
  const auto ref_norm = one.grad2d_norm().read<float>(s.cloud.size());

  Rasterizer batch(ctx);  // fresh: its sort's scratch starts small
  std::vector<RenderState> states;
  for (size_t i = 0; i < cams.size(); ++i) states.emplace_back(ctx);
  const uint64_t transfers0 = ctx.transfers(), submits0 = ctx.submits();
  batch.forward(params, cams, s.settings, {&states[0], &states[1], &states[2]});
  // Two submits and one download (the three intersection counts): the host's round trips,
  // whatever the number of frames.
  CHECK(ctx.transfers() - transfers0 == 1);
  CHECK(ctx.submits() - submits0 == 2);
  for (size_t i = 0; i < cams.size(); ++i) {
    INFO("frame " << i);
    REQUIRE(states[i].num_intersections() == isects[i]);
    REQUIRE(test::same_values(states[i].outputs().rgb.read<float>(3 * w * h), ref_rgb[i]));
  }
  const std::vector<const RenderState*> ptrs{&states[0], &states[1], &states[2]};
  const std::vector<const gpu::Buffer*> v_rgb(3, &vr);
  const auto pose = batch.backward(ptrs, params, v_rgb, va, grads);
  const GaussianCloud g = grads.download();
  REQUIRE(test::same_values(g.means, ref.means));
  REQUIRE(test::same_values(g.quats, ref.quats));
  REQUIRE(test::same_values(g.sh, ref.sh));
  REQUIRE(test::same_values(batch.grad2d_norm().read<float>(s.cloud.size()), ref_norm));
  REQUIRE(pose.size() == 3);
  for (size_t i = 0; i < 3; ++i)
    REQUIRE(test::same_values({pose[i].begin(), pose[i].end()}, {ref_pose[i].begin(), ref_pose[i].end()}));
  REQUIRE(batch.pose_gradient() == pose[2]);
  test::require_no_validation_messages();
}
