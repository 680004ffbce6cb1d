#include "splat/synthetic.h"

#include <cmath>
#include <random>

namespace evflow {

GaussianCloud synthetic_cloud(uint64_t seed, size_t n, int degree, const Camera& cam) {
  std::mt19937_64 rng(seed);
  auto uni = [&](double a, double b) { return a + (b - a) * (double(rng() >> 11) * (1.0 / 9007199254740992.0)); };
  auto normal = [&]() {
    double u1 = uni(1e-12, 1.0), u2 = uni(0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  };
  GaussianCloud c;
  c.resize(n, degree);
  const int K = c.coeffs();
  for (size_t i = 0; i < n; ++i) {
    const double z = uni(2.0, 10.0);
    const double px = uni(-0.1, 1.1) * cam.width, py = uni(-0.1, 1.1) * cam.height;
    const double xc = (px - cam.cx) / cam.fx * z, yc = (py - cam.cy) / cam.fy * z;
    // camera -> world: p_w = R^T (p_c - t)
    const double pc[3] = {xc - cam.t[0], yc - cam.t[1], z - cam.t[2]};
    for (int r = 0; r < 3; ++r)
      c.means[i * 3 + r] = float(cam.R[r] * pc[0] + cam.R[3 + r] * pc[1] + cam.R[6 + r] * pc[2]);
    const double sigma_px = std::exp(uni(std::log(0.5), std::log(6.0)));
    const double base = std::log(sigma_px * z / cam.fx);
    for (int k = 0; k < 3; ++k) c.log_scales[i * 3 + k] = float(base + uni(-0.7, 0.7));
    double q[4], qn = 0;
    for (double& v : q) {
      v = normal();
      qn += v * v;
    }
    for (int k = 0; k < 4; ++k) c.quats[i * 4 + k] = float(q[k] / std::sqrt(qn));
    c.opacity_logits[i] = float(uni(-2.0, 3.0));
    for (int k = 0; k < K; ++k)
      for (int ch = 0; ch < 3; ++ch) c.sh[(i * K + k) * 3 + ch] = float(k == 0 ? normal() * 0.8 : normal() * 0.1);
  }
  return c;
}

}  // namespace evflow
