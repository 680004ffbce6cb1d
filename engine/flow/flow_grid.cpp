#include "flow/flow_grid.h"

#include <algorithm>
#include <cmath>

namespace evflow::flow {

void grid_cell(double c, uint32_t size, uint32_t tiles, uint32_t& a, double& f) {
  const double g = c * tiles / size;
  const double fl = std::clamp(std::floor(g), 0.0, double(tiles - 1));
  a = uint32_t(fl);
  f = g - fl;
}

namespace {
// Flow at continuous pixel coordinates (x, y) (centres at +0.5).
void flow_at(const FlowGrid& g, uint32_t W, uint32_t H, double x, double y, double& u, double& v) {
  uint32_t a, b;
  double fa, fb;
  grid_cell(x, W, g.tiles, a, fa);
  grid_cell(y, H, g.tiles, b, fb);
  const size_t s = g.side(), i = b * s + a;
  const double w[4] = {(1 - fa) * (1 - fb), fa * (1 - fb), (1 - fa) * fb, fa * fb};
  const size_t n[4] = {i, i + 1, i + s, i + s + 1};
  u = v = 0;
  for (int k = 0; k < 4; ++k) {
    u += w[k] * g.nodes[n[k] * 2];
    v += w[k] * g.nodes[n[k] * 2 + 1];
  }
}
}  // namespace

std::vector<float> dense_flow(const FlowGrid& g, uint32_t W, uint32_t H) {
  std::vector<float> out(size_t(W) * H * 2);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      double u, v;
      flow_at(g, W, H, x + 0.5, y + 0.5, u, v);
      out[(size_t(y) * W + x) * 2] = float(u);
      out[(size_t(y) * W + x) * 2 + 1] = float(v);
    }
  return out;
}

FlowGrid refine(const FlowGrid& g, uint32_t tiles, uint32_t W, uint32_t H) {
  FlowGrid r(tiles);
  for (uint32_t b = 0; b <= tiles; ++b)
    for (uint32_t a = 0; a <= tiles; ++a) {
      double u, v;
      flow_at(g, W, H, double(a) * W / tiles, double(b) * H / tiles, u, v);
      r.nodes[(size_t(b) * r.side() + a) * 2] = float(u);
      r.nodes[(size_t(b) * r.side() + a) * 2 + 1] = float(v);
    }
  return r;
}

double grid_tv(const FlowGrid& g, double weight, std::vector<double>& grad, double eps) {
  const size_t s = g.side();
  const size_t pairs = 2 * s * (s - 1);
  double tv = 0;
  auto edge = [&](size_t i, size_t j) {
    const double du = g.nodes[j * 2] - g.nodes[i * 2], dv = g.nodes[j * 2 + 1] - g.nodes[i * 2 + 1];
    const double m = std::sqrt(du * du + dv * dv + eps * eps);
    tv += m;
    const double k = weight / (m * pairs);
    grad[j * 2] += k * du;
    grad[j * 2 + 1] += k * dv;
    grad[i * 2] -= k * du;
    grad[i * 2 + 1] -= k * dv;
  };
  for (size_t b = 0; b < s; ++b)
    for (size_t a = 0; a < s; ++a) {
      if (a + 1 < s) edge(b * s + a, b * s + a + 1);
      if (b + 1 < s) edge(b * s + a, (b + 1) * s + a);
    }
  return tv / pairs;
}

}  // namespace evflow::flow
