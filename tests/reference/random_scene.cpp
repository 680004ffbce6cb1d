#include "reference/random_scene.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace evflow::reference {

namespace {

// Portable distributions on top of std::mt19937_64 (whose output sequence the standard fixes).
class Rng {
 public:
  explicit Rng(uint64_t seed) : gen_(seed) {}
  double uniform01() { return double(gen_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform01(); }
  size_t index(size_t n) { return size_t(uniform01() * double(n)); }  // [0, n)
  double normal(double mean = 0.0, double sd = 1.0) {
    const double u1 = 1.0 - uniform01();  // (0, 1]
    const double u2 = uniform01();
    return mean + sd * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::mt19937_64 gen_;
};

enum class Kind { Normal, TileBorder, Behind, Beyond, Thin, Large };

}  // namespace

Camera test_camera(uint32_t width, uint32_t height) {
  return Camera::look_at(width, height, 60.0, {1.2, -0.7, -4.5}, {0.1, 0.2, 0.3}, {0.15, 1.0, 0.1});
}

GaussianCloud random_scene(uint64_t seed, size_t n, int sh_degree, const Camera& cam) {
  Rng rng(seed);
  GaussianCloud cloud;
  cloud.resize(n, sh_degree);
  const int K = cloud.coeffs();
  const double W = cam.width, H = cam.height;

  // Categories by count (at least one each once n >= 20), then shuffled.
  std::vector<Kind> kinds(n, Kind::Normal);
  auto count = [&](double frac) { return n >= 20 ? std::max<size_t>(1, size_t(std::lround(frac * double(n)))) : 0; };
  size_t at = 0;
  for (auto [kind, frac] : {std::pair{Kind::Behind, 0.03}, std::pair{Kind::Beyond, 0.03}, std::pair{Kind::Thin, 0.05},
                            std::pair{Kind::Large, 0.03}, std::pair{Kind::TileBorder, 0.12}})
    for (size_t c = count(frac); c > 0 && at < n; --c) kinds[at++] = kind;
  for (size_t i = n; i > 1; --i) std::swap(kinds[i - 1], kinds[rng.index(i)]);  // Fisher-Yates

  for (size_t i = 0; i < n; ++i) {
    const Kind kind = kinds[i];
    // Screen position and depth.
    double u = rng.uniform(0.0, W), v = rng.uniform(0.0, H), z = rng.uniform(1.5, 7.0);
    if (kind == Kind::TileBorder) {
      // mean within a pixel of a vertical and/or horizontal 16-px tile border
      const int mode = int(rng.index(3));
      const double tx = std::max(1.0, std::floor(W / 16.0 - 1e-9)), ty = std::max(1.0, std::floor(H / 16.0 - 1e-9));
      if (mode != 1) u = 16.0 * double(1 + rng.index(size_t(tx))) + rng.uniform(-1.0, 1.0);
      if (mode != 0) v = 16.0 * double(1 + rng.index(size_t(ty))) + rng.uniform(-1.0, 1.0);
    } else if (kind == Kind::Behind) {
      z = -rng.uniform(0.3, 4.0);
    } else if (kind == Kind::Beyond) {
      const double off = rng.uniform(0.05, 0.5);
      switch (rng.index(4)) {
        case 0:
          u = -off * W;
          break;
        case 1:
          u = W + off * W;
          break;
        case 2:
          v = -off * H;
          break;
        default:
          v = H + off * H;
          break;
      }
    }
    // Screen-space standard deviation -> world scale at this depth.
    double sigma_px = std::exp(rng.uniform(std::log(0.6), std::log(5.0)));
    if (kind == Kind::Large) sigma_px = rng.uniform(0.08, 0.2) * std::max(W, H);
    const double base = std::log(sigma_px * std::abs(z) / cam.fx);
    double ls[3];
    for (double& l : ls) l = base + rng.normal(0.0, 0.3);
    if (kind == Kind::Thin) ls[rng.index(3)] = base - 6.0;

    const double pc[3] = {(u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z};
    // world = R^T (pc - t)
    for (int r = 0; r < 3; ++r) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += cam.R[k * 3 + r] * (pc[k] - cam.t[k]);
      cloud.means[i * 3 + r] = float(s);
    }
    for (int r = 0; r < 3; ++r) cloud.log_scales[i * 3 + r] = float(ls[r]);
    double q[4], qn = 0;
    for (double& c : q) {
      c = rng.normal();
      qn += c * c;
    }
    qn = std::sqrt(qn);
    const double mag = rng.uniform(0.6, 1.6);
    for (int c = 0; c < 4; ++c) cloud.quats[i * 4 + c] = float(q[c] / qn * mag);
    cloud.opacity_logits[i] = float(rng.uniform(-3.0, 4.0));
    for (int k = 0; k < K; ++k)
      for (int c = 0; c < 3; ++c) cloud.sh[(i * K + k) * 3 + c] = float(rng.normal(0.0, k == 0 ? 0.5 : 0.1));
  }
  return cloud;
}

std::vector<float> random_weights(uint64_t seed, size_t n) {
  Rng rng(seed);
  std::vector<float> w(n);
  for (float& x : w) x = float(rng.uniform(-1.0, 1.0));
  return w;
}

}  // namespace evflow::reference
