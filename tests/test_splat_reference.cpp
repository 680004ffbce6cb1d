// Tests of the double-precision CPU splat reference itself (tests/reference/splat_reference.*)
// against closed forms, and of its fast local finite differences against full re-renders.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "reference/random_scene.h"
#include "reference/splat_reference.h"

using namespace evflow;
using namespace evflow::reference;

namespace {

// Isotropic Gaussian on the optical axis of simple_camera(): it projects to the centre of pixel (16, 16).
struct Iso {
  double z, scale, logit;
  std::array<double, 3> colour;  // target colour (stored as an SH DC coefficient)
};

constexpr double kFx = 40.0;

Camera simple_camera() {
  Camera c;
  c.width = 33;
  c.height = 33;
  c.fx = c.fy = kFx;
  c.cx = c.cy = 16.5;
  return c;
}

GaussianCloud iso_cloud(const std::vector<Iso>& gs, int degree = 0) {
  GaussianCloud c;
  c.resize(gs.size(), degree);
  const int K = c.coeffs();
  for (size_t i = 0; i < gs.size(); ++i) {
    c.means[i * 3 + 0] = 0.f;
    c.means[i * 3 + 1] = 0.f;
    c.means[i * 3 + 2] = float(gs[i].z);
    for (int k = 0; k < 3; ++k) c.log_scales[i * 3 + k] = float(std::log(gs[i].scale));
    // an unnormalised, non-trivial rotation: irrelevant for an isotropic Gaussian
    const float q[4] = {0.3f, -0.5f, 0.7f, 0.2f};
    for (int k = 0; k < 4; ++k) c.quats[i * 4 + k] = q[k];
    c.opacity_logits[i] = float(gs[i].logit);
    for (int ch = 0; ch < 3; ++ch) c.sh[(i * K) * 3 + ch] = float((gs[i].colour[ch] - 0.5) / kShC0);
  }
  return c;
}

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The (clamped) degree-0 colour of Gaussian i, channel ch.
double colour_of(const GaussianCloud& c, size_t i, int ch) {
  return std::max(0.0, kShC0 * double(c.sh[i * c.coeffs() * 3 + ch]) + 0.5);
}

struct Expected {
  double rgb[3], alpha, depth;
};

// Independent closed-form compositor for on-axis isotropic Gaussians of iso_cloud() seen by
// simple_camera() (no matrices, no conics: sigma_px = fx * s / z).
Expected expected_pixel(const GaussianCloud& c, int x, int y, const RenderSettings& s) {
  std::vector<size_t> order(c.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return c.means[a * 3 + 2] < c.means[b * 3 + 2]; });
  const double r2 = (x + 0.5 - 16.5) * (x + 0.5 - 16.5) + (y + 0.5 - 16.5) * (y + 0.5 - 16.5);
  double C[3] = {0, 0, 0}, D = 0, T = 1;
  for (size_t i : order) {
    const double z = c.means[i * 3 + 2];
    if (z < 0.01) continue;
    const double S = std::pow(kFx * std::exp(double(c.log_scales[i * 3])) / z, 2);
    double o = sigmoid(c.opacity_logits[i]);
    if (s.antialiased) o *= S / (S + 0.3);
    if (o < 1.0 / 255) continue;
    const double a = std::min(0.99, o * std::exp(-0.5 * r2 / (S + 0.3)));
    if (a < 1.0 / 255) continue;
    if (T * (1 - a) < 1e-4) break;
    const int K = c.coeffs();
    for (int ch = 0; ch < 3; ++ch) C[ch] += a * T * std::max(0.0, kShC0 * double(c.sh[i * K * 3 + ch]) + 0.5);
    D += a * T * z;
    T *= 1 - a;
  }
  Expected e;
  for (int ch = 0; ch < 3; ++ch) e.rgb[ch] = C[ch] + T * s.background[ch];
  e.alpha = 1 - T;
  e.depth = T < 1 ? D / (1 - T) : 0.0;
  return e;
}

void check_against_expected(const GaussianCloud& c, const RenderSettings& s, double tol = 1e-12) {
  const Camera cam = simple_camera();
  const RenderOutput r = render(c, cam, s);
  REQUIRE(r.width == 33);
  REQUIRE(r.height == 33);
  const size_t HW = 33 * 33;
  for (int y = 0; y < 33; ++y)
    for (int x = 0; x < 33; ++x) {
      const Expected e = expected_pixel(c, x, y, s);
      const size_t p = size_t(y) * 33 + x;
      INFO("pixel " << x << "," << y);
      for (int ch = 0; ch < 3; ++ch) REQUIRE(r.rgb[ch * HW + p] == Approx(e.rgb[ch]).margin(tol).epsilon(0));
      REQUIRE(r.alpha[p] == Approx(e.alpha).margin(tol).epsilon(0));
      REQUIRE(r.depth[p] == Approx(e.depth).margin(tol * 10).epsilon(0));
    }
}

size_t centre_pixel() { return 16 * 33 + 16; }

}  // namespace

TEST_CASE("reference: single isotropic Gaussian gives the analytic image", "[reference]") {
  RenderSettings s;
  s.background = {0.2f, 0.4f, 0.6f};
  const GaussianCloud c = iso_cloud({{5.0, 0.5, 1.0, {0.9, 0.3, 0.1}}});
  SECTION("plain") { check_against_expected(c, s); }
  SECTION("antialiased") {
    s.antialiased = true;
    check_against_expected(c, s);
  }
  // spot check of the centre pixel against the formula written out (no antialiasing)
  RenderSettings s0;
  s0.background = {0.2f, 0.4f, 0.6f};
  const RenderOutput r = render(c, simple_camera(), s0);
  const double o = sigmoid(double(c.opacity_logits[0]));
  REQUIRE(r.alpha[centre_pixel()] == Approx(o).epsilon(1e-14));
  REQUIRE(r.depth[centre_pixel()] == Approx(5.0).epsilon(1e-14));
  // pixel (20, 16): 4 px from the centre, sigma^2 = (40 * 0.5 / 5)^2 = 16
  const double sig2 = std::pow(kFx * std::exp(double(c.log_scales[0])) / 5.0, 2);
  REQUIRE(r.alpha[16 * 33 + 20] == Approx(o * std::exp(-0.5 * 16.0 / (sig2 + 0.3))).epsilon(1e-13));
  // background shows through with T = 1 - alpha
  const double col0 = colour_of(c, 0, 0);
  REQUIRE(r.rgb[16 * 33 + 20] ==
          Approx(r.alpha[16 * 33 + 20] * col0 + (1 - r.alpha[16 * 33 + 20]) * 0.2f).epsilon(1e-13));
  // far corner: untouched background
  REQUIRE(r.alpha[0] == 0.0);
  REQUIRE(r.rgb[2 * 33 * 33] == double(0.6f));
  REQUIRE(r.depth[0] == 0.0);
}

TEST_CASE("reference: overlapping Gaussians blend front to back, ties by index", "[reference]") {
  RenderSettings s;
  s.background = {0.1f, 0.1f, 0.1f};
  SECTION("depth order differs from index order") {
    const GaussianCloud c = iso_cloud({{6.0, 0.6, 0.5, {1.0, 0.0, 0.0}}, {4.0, 0.3, 0.0, {0.0, 1.0, 0.0}}});
    check_against_expected(c, s);
    const RenderOutput r = render(c, simple_camera(), s);
    // centre pixel: front (index 1, green) alpha 0.5, back (index 0, red) sigmoid(0.5)
    const double a1 = 0.5, a0 = sigmoid(0.5);
    const size_t p = centre_pixel(), HW = 33 * 33;
    const double g1 = colour_of(c, 1, 1), r0 = colour_of(c, 0, 0);
    REQUIRE(r.rgb[HW + p] ==
            Approx(a1 * g1 + a0 * (1 - a1) * colour_of(c, 0, 1) + (1 - a1) * (1 - a0) * 0.1f).epsilon(1e-13));
    REQUIRE(r.rgb[p] ==
            Approx(a0 * (1 - a1) * r0 + a1 * colour_of(c, 1, 0) + (1 - a1) * (1 - a0) * 0.1f).epsilon(1e-13));
    REQUIRE(r.depth[p] == Approx((a1 * 4.0 + a0 * (1 - a1) * 6.0) / (1 - (1 - a1) * (1 - a0))).epsilon(1e-13));
  }
  SECTION("equal depth: lower index first") {
    const GaussianCloud c = iso_cloud({{5.0, 0.5, 1.0, {1.0, 0.0, 0.0}}, {5.0, 0.4, 2.0, {0.0, 1.0, 0.0}}});
    const RenderOutput r = render(c, simple_camera(), s);
    const double a0 = sigmoid(double(c.opacity_logits[0])), a1 = sigmoid(double(c.opacity_logits[1]));
    const double red0 = colour_of(c, 0, 0), green1 = colour_of(c, 1, 1);
    const double green0 = colour_of(c, 0, 1);
    const size_t p = centre_pixel(), HW = 33 * 33;
    REQUIRE(r.rgb[HW + p] == Approx(a0 * green0 + (1 - a0) * a1 * green1 + (1 - a0) * (1 - a1) * 0.1f).epsilon(1e-13));
    REQUIRE(r.rgb[p] ==
            Approx(a0 * red0 + (1 - a0) * a1 * colour_of(c, 1, 0) + (1 - a0) * (1 - a1) * 0.1f).epsilon(1e-13));
    check_against_expected(c, s);
  }
}

TEST_CASE("reference: culling behind the camera, before near and beyond far", "[reference]") {
  RenderSettings s;
  s.background = {0.3f, 0.5f, 0.7f};
  GaussianCloud c =
      iso_cloud({{-5.0, 2.0, 6.0, {1, 1, 1}}, {0.005, 0.01, 6.0, {1, 1, 1}}, {12.0, 2.0, 6.0, {1, 1, 1}}});
  Camera cam = simple_camera();
  cam.far_plane = 10.0;
  const RenderOutput r = render(c, cam, s);
  for (size_t p = 0; p < 33 * 33; ++p) {
    REQUIRE(r.alpha[p] == 0.0);
    REQUIRE(r.depth[p] == 0.0);
    for (int ch = 0; ch < 3; ++ch) REQUIRE(r.rgb[ch * 33 * 33 + p] == double(s.background[ch]));
  }
  // the far one is visible once the far plane allows it
  cam.far_plane = 1e10;
  REQUIRE(render(c, cam, s).alpha[centre_pixel()] > 0.9);
}

TEST_CASE("reference: transmittance stop and the 1/255 alpha skip", "[reference]") {
  RenderSettings s;
  s.background = {0.25f, 0.5f, 0.75f};
  SECTION("T(1 - alpha) < 1e-4 stops the pixel before blending") {
    const double l98 = std::log(0.98 / 0.02), l90 = std::log(0.9 / 0.1);
    const GaussianCloud c = iso_cloud({{3.0, 0.5, l98, {0, 1, 0}},    // second: alpha 0.98
                                       {2.0, 0.5, 10.0, {1, 0, 0}},   // first: alpha clamped to 0.99
                                       {4.0, 0.5, l90, {0, 0, 1}},    // third: T*(1-0.9) = 2e-5 -> stop
                                       {5.0, 0.5, 0.0, {1, 1, 1}}});  // fourth: never reached
    const RenderOutput r = render(c, simple_camera(), s);
    const size_t p = centre_pixel(), HW = 33 * 33;
    const double a1 = 0.99, a2 = sigmoid(double(c.opacity_logits[0]));
    const double T = (1 - a1) * (1 - a2);
    REQUIRE(r.alpha[p] == Approx(1 - T).epsilon(1e-14));
    const double red1 = colour_of(c, 1, 0), red2 = colour_of(c, 0, 0);
    REQUIRE(r.rgb[p] == Approx(a1 * red1 + a2 * (1 - a1) * red2 + T * 0.25f).epsilon(1e-13));
    const double blue1 = colour_of(c, 1, 2), blue2 = colour_of(c, 0, 2);
    REQUIRE(r.rgb[2 * HW + p] == Approx(a1 * blue1 + a2 * (1 - a1) * blue2 + T * 0.75f).epsilon(1e-13));
    REQUIRE(r.depth[p] == Approx((a1 * 2.0 + a2 * (1 - a1) * 3.0) / (1 - T)).epsilon(1e-13));
    check_against_expected(c, s);
  }
  SECTION("alpha < 1/255 is skipped") {
    // o = sigmoid(1): alpha falls below 1/255 at r^2 > 2 (S + 0.3) ln(255 o) ~ 170, inside the image
    const GaussianCloud c = iso_cloud({{5.0, 0.5, 1.0, {0.8, 0.2, 0.6}}});
    const RenderOutput r = render(c, simple_camera(), s);
    const double o = sigmoid(double(c.opacity_logits[0])),
                 S = std::pow(kFx * std::exp(double(c.log_scales[0])) / 5.0, 2);
    int skipped = 0, kept_small = 0;
    for (int y = 0; y < 33; ++y)
      for (int x = 0; x < 33; ++x) {
        const double r2 = (x - 16.0) * (x - 16.0) + (y - 16.0) * (y - 16.0);
        const double a = o * std::exp(-0.5 * r2 / (S + 0.3));
        const size_t p = size_t(y) * 33 + x;
        if (a < 1.0 / 255) {
          ++skipped;
          REQUIRE(r.alpha[p] == 0.0);
          REQUIRE(r.rgb[p] == double(s.background[0]));
        } else {
          if (a < 2.0 / 255) ++kept_small;
          REQUIRE(r.alpha[p] == Approx(a).epsilon(1e-12));
        }
      }
    REQUIRE(skipped > 0);
    REQUIRE(kept_small > 0);
    // a Gaussian whose opacity is below 1/255 contributes nowhere
    const GaussianCloud faint = iso_cloud({{5.0, 0.5, std::log((1.0 / 255) / (1 - 1.0 / 255)) - 1e-3, {1, 1, 1}}});
    const RenderOutput rf = render(faint, simple_camera(), s);
    for (double a : rf.alpha) REQUIRE(a == 0.0);
  }
}

TEST_CASE("reference: SH view dependence and active degree", "[reference]") {
  GaussianCloud c = iso_cloud({{5.0, 0.5, 8.0, {0.4, 0.5, 0.6}}}, 1);
  // on the optical axis of the identity camera, dir = (0, 0, 1): colour += SH_C1 * sh[k=2]
  for (int ch = 0; ch < 3; ++ch) c.sh[(2 * 3) + ch] = 0.25f * float(ch + 1);
  RenderSettings s;
  const size_t p = centre_pixel(), HW = 33 * 33;
  const double a = 0.99;  // clamped
  const RenderOutput r1 = render(c, simple_camera(), s);
  s.sh_degree = 0;
  const RenderOutput r0 = render(c, simple_camera(), s);
  for (int ch = 0; ch < 3; ++ch) {
    const double dc = kShC0 * double(c.sh[ch]) + 0.5;
    REQUIRE(r1.rgb[ch * HW + p] == Approx(a * (dc + kShC1 * double(c.sh[6 + ch]))).epsilon(1e-13));
    REQUIRE(r0.rgb[ch * HW + p] == Approx(a * dc).epsilon(1e-13));
  }
  // colours are clamped at 0
  c.sh[0] = -10.f;
  REQUIRE(render(c, simple_camera(), s).rgb[p] == 0.0);
}

TEST_CASE("reference: finite differences match closed forms", "[reference]") {
  RenderSettings s;
  s.background = {0.3f, 0.3f, 0.3f};
  const Camera cam = simple_camera();
  const size_t HW = 33 * 33;
  const GaussianCloud c = iso_cloud({{6.0, 0.6, 0.5, {0.7, 0.6, 0.5}}, {4.0, 0.3, 0.2, {0.4, 0.5, 0.6}}});
  auto alpha_of = [&](size_t i, int x, int y) {  // alpha of Gaussian i at pixel (x, y)
    const double z = c.means[i * 3 + 2], S = std::pow(kFx * std::exp(double(c.log_scales[i * 3])) / z, 2);
    const double r2 = (x - 16.0) * (x - 16.0) + (y - 16.0) * (y - 16.0);
    const double a = std::min(0.99, sigmoid(double(c.opacity_logits[i])) * std::exp(-0.5 * r2 / (S + 0.3)));
    return a < 1.0 / 255 ? 0.0 : a;
  };

  SECTION("d rgb / d SH DC = SH_C0 alpha T, summed with random weights") {
    const std::vector<float> v_rgb = random_weights(7, 3 * HW), v_alpha(HW, 0.f);
    const FiniteDifferences fd(c, cam, s, v_rgb, v_alpha);
    for (int ch = 0; ch < 3; ++ch) {
      double back = 0, front = 0;
      for (int y = 0; y < 33; ++y)
        for (int x = 0; x < 33; ++x) {
          const double af = alpha_of(1, x, y), ab = alpha_of(0, x, y);
          const double w = v_rgb[ch * HW + y * 33 + x];
          front += w * kShC0 * af;
          back += w * kShC0 * ab * (1 - af);
        }
      REQUIRE(fd.param(Param::Sh, 1, ch, 1e-3) == Approx(front).epsilon(1e-9));
      REQUIRE(fd.param(Param::Sh, 0, ch, 1e-3) == Approx(back).epsilon(1e-9));
      // a full re-render gives the same
      REQUIRE(fd.param_full_render(Param::Sh, 0, ch, 1e-3) == Approx(back).epsilon(1e-9));
    }
  }
  SECTION("d alpha / d logit of the front Gaussian at one pixel") {
    std::vector<float> v_rgb(3 * HW, 0.f), v_alpha(HW, 0.f);
    v_alpha[14 * 33 + 19] = 1.f;  // pixel (19, 14)
    const FiniteDifferences fd(c, cam, s, v_rgb, v_alpha);
    // alpha = 1 - (1 - a_f)(1 - a_b); a_f = sigmoid(l) g  ->  d alpha/dl = sigmoid'(l) g (1 - a_b)
    const double l = c.opacity_logits[1], sg = sigmoid(l);
    const double g = alpha_of(1, 19, 14) / sg;
    const double expect = sg * (1 - sg) * g * (1 - alpha_of(0, 19, 14));
    REQUIRE(fd.param(Param::OpacityLogit, 1, 0, 1e-4) == Approx(expect).epsilon(1e-7));
    REQUIRE(fd.param_full_render(Param::OpacityLogit, 1, 0, 1e-4) == Approx(expect).epsilon(1e-7));
  }
}

TEST_CASE("reference: local-region finite differences equal full re-render finite differences", "[reference]") {
  const Camera cam = test_camera(64, 48);
  const GaussianCloud c = random_scene(11, 120, 3, cam);
  const size_t HW = 64 * 48;
  RenderSettings s;
  s.background = {0.1f, 0.2f, 0.3f};
  s.antialiased = GENERATE(false, true);
  const FiniteDifferences fd(c, cam, s, random_weights(3, 3 * HW), random_weights(4, HW));
  const Param params[] = {Param::Mean, Param::LogScale, Param::Quat, Param::OpacityLogit, Param::Sh};
  int nonzero = 0, checked = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Param p = params[i % 5];
    const int comp = int(i % size_t(param_components(p, c)));
    for (double h : {1e-4, 0.05}) {  // a large h moves boxes and depth order substantially
      const double local = fd.param(p, i, comp, h), full = fd.param_full_render(p, i, comp, h);
      INFO("gaussian " << i << " param " << int(p) << " comp " << comp << " h " << h);
      REQUIRE(std::abs(local - full) <= 1e-12 * (1.0 + std::abs(full)));  // bitwise equal in practice
      nonzero += local != 0.0;
      ++checked;
    }
    // mean along every axis with a large step, which reorders Gaussians in depth
    if (i % 7 == 0)
      for (int k = 0; k < 3; ++k) {
        const double local = fd.param(Param::Mean, i, k, 0.3), full = fd.param_full_render(Param::Mean, i, k, 0.3);
        REQUIRE(std::abs(local - full) <= 1e-12 * (1.0 + std::abs(full)));  // bitwise equal in practice
      }
  }
  REQUIRE(nonzero > checked / 2);
  // the base loss agrees with weighted_loss
  REQUIRE(fd.loss() ==
          Approx(weighted_loss(c, cam, s, random_weights(3, 3 * HW), random_weights(4, HW))).epsilon(1e-12));
}

TEST_CASE("reference: pose finite differences of a translation along z", "[reference]") {
  RenderSettings s;
  s.antialiased = true;  // makes the centre alpha depend on the projected size
  const Camera cam = simple_camera();
  const size_t HW = 33 * 33;
  const GaussianCloud c = iso_cloud({{5.0, 0.1, 1.5, {0.5, 0.5, 0.5}}});
  // moving the camera forward by d (c2w * Exp(d e_z)) reduces the depth by d
  const RenderOutput moved = render(c, cam.perturbed({0, 0, 0.5, 0, 0, 0}), s);
  REQUIRE(moved.depth[centre_pixel()] == Approx(4.5).epsilon(1e-13));
  const RenderOutput back = render(c, cam.perturbed({0, 0, -1.0, 0, 0, 0}), s);
  REQUIRE(back.depth[centre_pixel()] == Approx(6.0).epsilon(1e-13));

  std::vector<float> v_rgb(3 * HW, 0.f), v_alpha(HW, 0.f);
  v_alpha[centre_pixel()] = 1.f;
  const FiniteDifferences fd(c, cam, s, v_rgb, v_alpha);
  // alpha = sigmoid(l) S / (S + 0.3), S = (fx s / (z - d))^2, dS/dd = 2 S / z at d = 0
  const double z = 5.0, S = std::pow(kFx * std::exp(double(c.log_scales[0])) / z, 2);
  const double expect = sigmoid(double(c.opacity_logits[0])) * 0.3 / ((S + 0.3) * (S + 0.3)) * 2 * S / z;
  const auto g = fd.pose(1e-5);
  REQUIRE(g[2] == Approx(expect).epsilon(1e-6));
  // every other direction moves the Gaussian symmetrically off the pixel: zero first derivative
  for (int i : {0, 1, 3, 4, 5}) REQUIRE(std::abs(g[i]) < 1e-6 * std::abs(expect));
}

TEST_CASE("reference: random scene is deterministic and hard", "[reference]") {
  const Camera cam = test_camera(160, 120);
  const GaussianCloud a = random_scene(42, 2000, 3, cam), b = random_scene(42, 2000, 3, cam);
  REQUIRE(a.means == b.means);
  REQUIRE(a.sh == b.sh);
  REQUIRE(a.quats == b.quats);
  REQUIRE(random_scene(43, 2000, 3, cam).means != a.means);
  a.validate("random scene");
  int behind = 0, outside = 0, thin = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    double p[3];
    for (int r = 0; r < 3; ++r)
      p[r] = cam.R[r * 3] * a.means[i * 3] + cam.R[r * 3 + 1] * a.means[i * 3 + 1] +
             cam.R[r * 3 + 2] * a.means[i * 3 + 2] + cam.t[r];
    if (p[2] < 0) {
      ++behind;
      continue;
    }
    const double u = cam.fx * p[0] / p[2] + cam.cx, v = cam.fy * p[1] / p[2] + cam.cy;
    if (u < 0 || u > 160 || v < 0 || v > 120) ++outside;
    const float* ls = &a.log_scales[i * 3];
    if (std::max({ls[0], ls[1], ls[2]}) - std::min({ls[0], ls[1], ls[2]}) > 4.f) ++thin;
  }
  REQUIRE(behind == 60);
  REQUIRE(outside >= 60);
  REQUIRE(thin >= 100);
  const auto w = random_weights(1, 1000);
  REQUIRE(*std::min_element(w.begin(), w.end()) >= -1.f);
  REQUIRE(*std::max_element(w.begin(), w.end()) <= 1.f);
  const RenderOutput r = render(a, cam, RenderSettings{});
  double mean_alpha = 0;
  for (double x : r.alpha) mean_alpha += x / r.alpha.size();
  REQUIRE(mean_alpha > 0.5);
}

// Timing of the reference at the size the GPU tests use (hidden: run with "[.reference-bench]").
TEST_CASE("reference: timing", "[.reference-bench]") {
  const Camera cam = test_camera(160, 120);
  const GaussianCloud c = random_scene(1, 2000, 3, cam);
  const size_t HW = 160 * 120;
  auto t0 = std::chrono::steady_clock::now();
  const RenderOutput r = render(c, cam, RenderSettings{});
  auto t1 = std::chrono::steady_clock::now();
  const FiniteDifferences fd(c, cam, RenderSettings{}, random_weights(2, 3 * HW), random_weights(3, HW));
  auto t2 = std::chrono::steady_clock::now();
  double acc = 0;
  int count = 0;
  for (size_t i = 0; i < c.size(); i += 2)
    for (Param p : {Param::Mean, Param::LogScale, Param::Quat, Param::OpacityLogit, Param::Sh}) {
      acc += fd.param(p, i, 0, 1e-4);
      ++count;
    }
  auto t3 = std::chrono::steady_clock::now();
  const auto pose = fd.pose(1e-4);
  auto t4 = std::chrono::steady_clock::now();
  auto ms = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  std::printf("render 2000 @160x120: %.1f ms; FD setup %.1f ms; %d param FDs %.1f ms (%.3f ms each); pose FD %.1f ms\n",
              ms(t0, t1), ms(t1, t2), count, ms(t2, t3), ms(t2, t3) / count, ms(t3, t4));
  REQUIRE(r.alpha.size() == HW);
  REQUIRE(std::isfinite(acc + pose[0]));
}
