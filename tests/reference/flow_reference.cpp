#include "reference/flow_reference.h"

#include <algorithm>
#include <cmath>

#include "flow/flow_layout.h"

namespace evflow::reference {

namespace {

double gauss(int d) {
  const double sigma = shaderio::kFlowBlurSigma;
  double s = 0;
  for (int k = -shaderio::kFlowBlurRadius; k <= shaderio::kFlowBlurRadius; ++k)
    s += std::exp(-0.5 * k * k / (sigma * sigma));
  return std::exp(-0.5 * d * d / (sigma * sigma)) / s;
}

std::vector<double> blur(const std::vector<double>& img, int W, int H, int dx, int dy) {
  std::vector<double> out(img.size(), 0.0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int d = -shaderio::kFlowBlurRadius; d <= shaderio::kFlowBlurRadius; ++d) {
        const int qx = x + d * dx, qy = y + d * dy;
        if (qx >= 0 && qy >= 0 && qx < W && qy < H) out[size_t(y) * W + x] += gauss(d) * img[size_t(qy) * W + qx];
      }
  return out;
}

void vote(std::vector<double>& img, int W, int H, double qx, double qy) {
  const double gx = qx - 0.5, gy = qy - 0.5;
  const int x0 = int(std::floor(gx)), y0 = int(std::floor(gy));
  const double fx = gx - x0, fy = gy - y0;
  for (int c = 0; c < 4; ++c) {
    const int x = x0 + (c & 1), y = y0 + (c >> 1);
    if (x < 0 || y < 0 || x >= W || y >= H) continue;
    img[size_t(y) * W + x] += ((c & 1) ? fx : 1 - fx) * ((c >> 1) ? fy : 1 - fy);
  }
}

// Flow of a grid at pixel (x, y), in double.
void flow_at(const flow::FlowGrid& g, int W, int H, int x, int y, double& u, double& v) {
  uint32_t a, b;
  double fa, fb;
  flow::grid_cell(x + 0.5, uint32_t(W), g.tiles, a, fa);
  flow::grid_cell(y + 0.5, uint32_t(H), g.tiles, b, fb);
  const size_t s = g.side(), i = b * s + a;
  const double w[4] = {(1 - fa) * (1 - fb), fa * (1 - fb), (1 - fa) * fb, fa * fb};
  const size_t n[4] = {i, i + 1, i + s, i + s + 1};
  u = v = 0;
  for (int k = 0; k < 4; ++k) u += w[k] * double(g.nodes[n[k] * 2]), v += w[k] * double(g.nodes[n[k] * 2 + 1]);
}

}  // namespace

double flow_image_contrast(const std::vector<double>& iwe, int W, int H) {
  const std::vector<double> b = blur(blur(iwe, W, H, 1, 0), W, H, 0, 1);
  auto at = [&](int x, int y) { return x < 0 || y < 0 || x >= W || y >= H ? 0.0 : b[size_t(y) * W + x]; };
  double g = 0;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double gx = 0.5 * (at(x + 1, y) - at(x - 1, y)), gy = 0.5 * (at(x, y + 1) - at(x, y - 1));
      g += gx * gx + gy * gy;
    }
  return g;
}

double flow_contrast(const flow::PixelEvents& ev, const std::vector<double>& frame_u,
                     const std::vector<flow::FlowGrid>& grids, const std::vector<double>& scale, int image_scale,
                     uint32_t stride) {
  const int W = int(ev.width), H = int(ev.height);
  const int IW = (W + image_scale - 1) / image_scale, IH = (H + image_scale - 1) / image_scale;
  double total = 0;
  for (int r = 0; r < 3; ++r) {
    const double tr = 0.5 * r;
    std::vector<double> img(size_t(IW) * IH, 0.0);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        std::vector<double> u(grids.size()), v(grids.size());
        for (size_t j = 0; j < grids.size(); ++j) flow_at(grids[j], W, H, x, y, u[j], v[j]);
        const size_t pix = size_t(y) * W + x;
        for (uint32_t e = ev.first[pix]; e < ev.first[pix + 1]; ++e) {
          if (e % stride != 0) continue;
          double dx = 0, dy = 0;
          for (size_t j = 0; j < grids.size(); ++j) {  // the signed part of [t, tr] in interval j
            const double a = frame_u[j], b = frame_u[j + 1];
            const double lever = (std::clamp(tr, a, b) - std::clamp(double(ev.time[e]), a, b)) / (b - a);
            dx += lever * u[j], dy += lever * v[j];
          }
          vote(img, IW, IH, (x + 0.5 + dx) / image_scale, (y + 0.5 + dy) / image_scale);
        }
      }
    total += scale[r] * flow_image_contrast(img, IW, IH);
  }
  return total;
}

}  // namespace evflow::reference
