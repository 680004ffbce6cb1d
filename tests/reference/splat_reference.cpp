#include "reference/splat_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace evflow::reference {

namespace {

constexpr double kShC2[5] = {1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792,
                             0.5462742152960396};
constexpr double kShC3[7] = {-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
                             -0.4570457994644658, 1.445305721320277, -0.5900435899266435};
constexpr double kMinAlpha = 1.0 / 255.0;
constexpr double kMaxAlpha = 0.99;
constexpr double kTransmittanceStop = 1e-4;
constexpr int kTile = 8;  // the reference's own binning; any size gives the same image

// The cloud in double, converted once.
struct CloudD {
  int degree = 0, coeffs = 1;
  size_t n = 0;
  std::vector<double> means, log_scales, quats, logits, sh;

  explicit CloudD(const GaussianCloud& c) {
    c.validate("reference cloud");
    degree = c.sh_degree;
    coeffs = c.coeffs();
    n = c.size();
    auto cv = [](const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); };
    means = cv(c.means);
    log_scales = cv(c.log_scales);
    quats = cv(c.quats);
    logits = cv(c.opacity_logits);
    sh = cv(c.sh);
  }
};

// One Gaussian's parameters (pointers into a CloudD or a perturbed local copy).
struct GaussianD {
  const double* mean;
  const double* log_scale;
  const double* quat;
  double logit;
  const double* sh;  // coeffs*3
};

GaussianD gaussian_of(const CloudD& c, size_t i) {
  return {&c.means[i * 3], &c.log_scales[i * 3], &c.quats[i * 4], c.logits[i], &c.sh[i * c.coeffs * 3]};
}

// A projected Gaussian. valid == false: culled (contributes to no pixel).
struct Proj {
  bool valid = false;
  double depth = 0;
  double mx = 0, my = 0;
  double conic[3] = {0, 0, 0};
  double opacity = 0;
  double color[3] = {0, 0, 0};
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;  // inclusive pixel range whose centres lie in the bounding box
};

struct Context {
  const Camera* cam;
  int active_degree;
  bool antialiased;
  std::array<double, 3> campos;
  double bg[3];
};

Context make_context(const Camera& cam, const RenderSettings& s, int cloud_degree) {
  Context ctx;
  ctx.cam = &cam;
  // Active degree: -1 = the cloud's; a request above the cloud's degree is clamped to it.
  ctx.active_degree = s.sh_degree < 0 ? cloud_degree : std::min(s.sh_degree, cloud_degree);
  ctx.antialiased = s.antialiased;
  ctx.campos = cam.center();
  for (int c = 0; c < 3; ++c) ctx.bg[c] = s.background[c];
  return ctx;
}

void sh_color(const double dir[3], const double* sh, int degree, double out[3]) {
  const double x = dir[0], y = dir[1], z = dir[2];
  const double xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
  for (int c = 0; c < 3; ++c) {
    auto k = [&](int i) { return sh[i * 3 + c]; };
    double r = kShC0 * k(0);
    if (degree > 0) {
      r = r - kShC1 * y * k(1) + kShC1 * z * k(2) - kShC1 * x * k(3);
      if (degree > 1) {
        r = r + kShC2[0] * xy * k(4) + kShC2[1] * yz * k(5) + kShC2[2] * (2.0 * zz - xx - yy) * k(6) +
            kShC2[3] * xz * k(7) + kShC2[4] * (xx - yy) * k(8);
        if (degree > 2) {
          r = r + kShC3[0] * y * (3.0 * xx - yy) * k(9) + kShC3[1] * xy * z * k(10) +
              kShC3[2] * y * (4.0 * zz - xx - yy) * k(11) + kShC3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * k(12) +
              kShC3[4] * x * (4.0 * zz - xx - yy) * k(13) + kShC3[5] * z * (xx - yy) * k(14) +
              kShC3[6] * x * (xx - 3.0 * yy) * k(15);
        }
      }
    }
    out[c] = std::max(r + 0.5, 0.0);
  }
}

// docs/rasterizer.md "Projection (one Gaussian)", steps 1-8.
Proj project(const GaussianD& g, const Context& ctx) {
  Proj P;
  const Camera& cam = *ctx.cam;
  const auto& R = cam.R;
  // 1. camera-space mean
  double p[3];
  for (int i = 0; i < 3; ++i)
    p[i] = R[i * 3] * g.mean[0] + R[i * 3 + 1] * g.mean[1] + R[i * 3 + 2] * g.mean[2] + cam.t[i];
  if (!(p[2] >= cam.near_plane && p[2] <= cam.far_plane)) return P;
  // 2. covariance
  const double qn =
      std::sqrt(g.quat[0] * g.quat[0] + g.quat[1] * g.quat[1] + g.quat[2] * g.quat[2] + g.quat[3] * g.quat[3]);
  const double w = g.quat[0] / qn, x = g.quat[1] / qn, y = g.quat[2] / qn, z = g.quat[3] / qn;
  const double Rq[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                        2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                        2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  double s2[3];
  for (int i = 0; i < 3; ++i) s2[i] = std::exp(2.0 * g.log_scale[i]);
  double S[9];  // Rq diag(s^2) Rq^T
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += Rq[i * 3 + k] * s2[k] * Rq[j * 3 + k];
      S[i * 3 + j] = a;
    }
  double RS[9], Sc[9];  // R S, then R S R^T
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += R[i * 3 + k] * S[k * 3 + j];
      RS[i * 3 + j] = a;
    }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += RS[i * 3 + k] * R[j * 3 + k];
      Sc[i * 3 + j] = a;
    }
  // 3. clamped Jacobian
  const double W = cam.width, H = cam.height;
  const double lim_x = 1.3 * 0.5 * W / cam.fx, lim_y = 1.3 * 0.5 * H / cam.fy;
  const double u = std::clamp(p[0] / p[2], -lim_x, lim_x), v = std::clamp(p[1] / p[2], -lim_y, lim_y);
  const double J[6] = {cam.fx / p[2], 0, -cam.fx * u / p[2], 0, cam.fy / p[2], -cam.fy * v / p[2]};
  // 4. 2D covariance, dilation, conic
  double JS[6];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += J[i * 3 + k] * Sc[k * 3 + j];
      JS[i * 3 + j] = a;
    }
  double S2[4];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      double a = 0;
      for (int k = 0; k < 3; ++k) a += JS[i * 3 + k] * J[j * 3 + k];
      S2[i * 2 + j] = a;
    }
  const double a = S2[0], b = 0.5 * (S2[1] + S2[2]), c = S2[3];
  const double ad = a + 0.3, cd = c + 0.3;
  const double det = ad * cd - b * b;
  if (!(det > 0)) return P;
  // 5. opacity
  double o = 1.0 / (1.0 + std::exp(-g.logit));
  if (ctx.antialiased) o *= std::sqrt(std::max(0.0, (a * c - b * b) / det));
  // 8. (first part) opacity cull
  if (!(o >= kMinAlpha)) return P;
  // 6. mean2d
  P.mx = cam.fx * p[0] / p[2] + cam.cx;
  P.my = cam.fy * p[1] / p[2] + cam.cy;
  // 8. support and bounding box. The box is padded by a tiny relative margin: it only selects
  // candidate pixels, the per-pixel alpha test decides.
  const double q_max = 2.0 * std::log(255.0 * o);
  const double rx = std::sqrt(q_max * ad) * (1 + 1e-9) + 1e-9, ry = std::sqrt(q_max * cd) * (1 + 1e-9) + 1e-9;
  // pixel x is in the box when |mx - (x + 0.5)| <= rx
  const double fx0 = std::ceil(P.mx - rx - 0.5), fx1 = std::floor(P.mx + rx - 0.5);
  const double fy0 = std::ceil(P.my - ry - 0.5), fy1 = std::floor(P.my + ry - 0.5);
  if (!(fx1 >= 0 && fy1 >= 0 && fx0 <= W - 1 && fy0 <= H - 1 && fx0 <= fx1 && fy0 <= fy1)) return P;
  P.x0 = static_cast<int>(std::max(fx0, 0.0));
  P.x1 = static_cast<int>(std::min(fx1, W - 1));
  P.y0 = static_cast<int>(std::max(fy0, 0.0));
  P.y1 = static_cast<int>(std::min(fy1, H - 1));
  // 7. colour
  double dir[3] = {g.mean[0] - ctx.campos[0], g.mean[1] - ctx.campos[1], g.mean[2] - ctx.campos[2]};
  const double dl = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
  for (double& d : dir) d /= dl;
  sh_color(dir, g.sh, ctx.active_degree, P.color);

  P.depth = p[2];
  P.conic[0] = cd / det;
  P.conic[1] = -b / det;
  P.conic[2] = ad / det;
  P.opacity = o;
  P.valid = true;
  return P;
}

// Front-to-back order: depth, ties by lower index.
inline bool before(const Proj& a, size_t ia, const Proj& b, size_t ib) {
  return a.depth < b.depth || (a.depth == b.depth && ia < ib);
}

// Projections of every Gaussian, depth order, and per-tile candidate lists (in depth order).
struct Scene {
  uint32_t W = 0, H = 0, tiles_x = 0, tiles_y = 0;
  std::vector<Proj> proj;
  std::vector<std::vector<uint32_t>> tiles;

  Scene(const CloudD& cloud, const Context& ctx) : W(ctx.cam->width), H(ctx.cam->height) {
    proj.resize(cloud.n);
    for (size_t i = 0; i < cloud.n; ++i) proj[i] = project(gaussian_of(cloud, i), ctx);
    std::vector<uint32_t> order;
    for (size_t i = 0; i < cloud.n; ++i)
      if (proj[i].valid) order.push_back(static_cast<uint32_t>(i));
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return before(proj[a], a, proj[b], b); });
    tiles_x = (W + kTile - 1) / kTile;
    tiles_y = (H + kTile - 1) / kTile;
    tiles.assign(size_t(tiles_x) * tiles_y, {});
    for (uint32_t i : order) {
      const Proj& P = proj[i];
      for (int ty = P.y0 / kTile; ty <= P.y1 / kTile; ++ty)
        for (int tx = P.x0 / kTile; tx <= P.x1 / kTile; ++tx) tiles[size_t(ty) * tiles_x + tx].push_back(i);
    }
  }
  const std::vector<uint32_t>& tile_of(int x, int y) const { return tiles[size_t(y / kTile) * tiles_x + x / kTile]; }
};

// Accumulated state of one pixel.
struct PixelState {
  double C[3] = {0, 0, 0};
  double D = 0;
  double T = 1;
  uint32_t stop = UINT32_MAX;  // the Gaussian at which the transmittance stop ended the pixel
};

// alpha of a projected Gaussian at the centre of pixel (x, y).
inline double alpha_at(const Proj& P, int x, int y) {
  const double dx = P.mx - (x + 0.5), dy = P.my - (y + 0.5);
  const double power = -0.5 * (P.conic[0] * dx * dx + 2.0 * P.conic[1] * dx * dy + P.conic[2] * dy * dy);
  return std::min(kMaxAlpha, P.opacity * std::exp(power));
}

inline bool in_box(const Proj& P, int x, int y) { return P.valid && x >= P.x0 && x <= P.x1 && y >= P.y0 && y <= P.y1; }

// Whether blending P at (x, y) does anything (otherwise it is skipped by the box or alpha test).
inline bool touches(const Proj& P, int x, int y) { return in_box(P, x, y) && alpha_at(P, x, y) >= kMinAlpha; }

// Blends one Gaussian into the pixel (docs "Compositing"). Returns false when the pixel stops.
inline bool blend(const Proj& P, int x, int y, PixelState& s) {
  if (x < P.x0 || x > P.x1 || y < P.y0 || y > P.y1) return true;
  const double alpha = alpha_at(P, x, y);
  if (alpha < kMinAlpha) return true;
  const double Tn = s.T * (1.0 - alpha);
  if (Tn < kTransmittanceStop) return false;
  const double wgt = alpha * s.T;
  for (int c = 0; c < 3; ++c) s.C[c] += wgt * P.color[c];
  s.D += wgt * P.depth;
  s.T = Tn;
  return true;
}

// Continues the front-to-back walk of `list` from position k with state s; Gaussian sub_idx of
// the list is skipped and, when sub != nullptr, *sub is blended at its own place in the order.
void continue_merge(const Scene& scene, const std::vector<uint32_t>& list, size_t k, int x, int y, size_t sub_idx,
                    const Proj* sub, PixelState& s) {
  bool sub_pending = sub != nullptr;
  for (; k < list.size(); ++k) {
    const uint32_t j = list[k];
    if (j == sub_idx) continue;
    const Proj& P = scene.proj[j];
    if (sub_pending && before(*sub, sub_idx, P, j)) {
      sub_pending = false;
      if (!blend(*sub, x, y, s)) {
        s.stop = uint32_t(sub_idx);
        return;
      }
    }
    if (!blend(P, x, y, s)) {
      s.stop = j;
      return;
    }
  }
  if (sub_pending && !blend(*sub, x, y, s)) s.stop = uint32_t(sub_idx);
}

// Composites pixel (x, y) of `scene`; when sub != nullptr, Gaussian sub_idx is replaced by *sub
// (placed at its own depth in the order, whether or not the original was in this tile's list).
PixelState composite(const Scene& scene, int x, int y, size_t sub_idx = SIZE_MAX, const Proj* sub = nullptr) {
  PixelState s;
  continue_merge(scene, scene.tile_of(x, y), 0, x, y, sub_idx, sub != nullptr && in_box(*sub, x, y) ? sub : nullptr, s);
  return s;
}

// Both perturbed evaluations of one pixel, sharing the walk up to the first place where either
// perturbed Gaussian enters. Bitwise the same states as two composite() calls.
void composite_pair(const Scene& scene, int x, int y, size_t g, const Proj& Pp, const Proj& Pm, PixelState& sp,
                    PixelState& sm) {
  const std::vector<uint32_t>& list = scene.tile_of(x, y);
  const Proj* subp = touches(Pp, x, y) ? &Pp : nullptr;
  const Proj* subm = touches(Pm, x, y) ? &Pm : nullptr;
  PixelState s;
  size_t k = 0;
  for (; k < list.size(); ++k) {
    const uint32_t j = list[k];
    if (j == g) continue;
    const Proj& P = scene.proj[j];
    if ((subp && before(Pp, g, P, j)) || (subm && before(Pm, g, P, j))) break;
    if (!blend(P, x, y, s)) {  // stopped before either: both evaluations end here
      s.stop = j;
      sp = sm = s;
      return;
    }
  }
  sp = s;
  sm = s;
  continue_merge(scene, list, k, x, y, g, subp, sp);
  continue_merge(scene, list, k, x, y, g, subm, sm);
}

double pixel_loss(const PixelState& s, size_t pix, size_t HW, const double bg[3], const std::vector<float>& v_rgb,
                  const std::vector<float>& v_alpha) {
  double l = 0;
  for (int c = 0; c < 3; ++c) l += double(v_rgb[c * HW + pix]) * (s.C[c] + s.T * bg[c]);
  l += double(v_alpha[pix]) * (1.0 - s.T);
  return l;
}

RenderOutput render_scene(const Scene& scene, const Context& ctx) {
  RenderOutput out;
  out.width = scene.W;
  out.height = scene.H;
  const size_t HW = size_t(scene.W) * scene.H;
  out.rgb.assign(3 * HW, 0.0);
  out.alpha.assign(HW, 0.0);
  out.depth.assign(HW, 0.0);
  for (uint32_t y = 0; y < scene.H; ++y)
    for (uint32_t x = 0; x < scene.W; ++x) {
      const PixelState s = composite(scene, int(x), int(y));
      const size_t pix = size_t(y) * scene.W + x;
      for (int c = 0; c < 3; ++c) out.rgb[c * HW + pix] = s.C[c] + s.T * ctx.bg[c];
      out.alpha[pix] = 1.0 - s.T;
      out.depth[pix] = s.T < 1.0 ? s.D / (1.0 - s.T) : 0.0;
    }
  return out;
}

void check_weights(const Camera& cam, const std::vector<float>& v_rgb, const std::vector<float>& v_alpha) {
  const size_t HW = size_t(cam.width) * cam.height;
  if (v_rgb.size() != 3 * HW || v_alpha.size() != HW)
    throw std::invalid_argument("reference: v_rgb must have 3*H*W and v_alpha H*W values (got " +
                                std::to_string(v_rgb.size()) + ", " + std::to_string(v_alpha.size()) + ")");
}

}  // namespace

struct FiniteDifferences::Impl {
  CloudD cloud;
  Camera cam;
  RenderSettings settings;
  std::vector<float> v_rgb, v_alpha;
  Context ctx;
  Scene scene;
  std::vector<uint32_t> stop;  // per pixel: the Gaussian where the base render stopped, or UINT32_MAX

  Impl(const GaussianCloud& c, const Camera& cm, const RenderSettings& s, std::vector<float> vr, std::vector<float> va)
      : cloud(c),
        cam(cm),
        settings(s),
        v_rgb(std::move(vr)),
        v_alpha(std::move(va)),
        ctx(make_context(cam, settings, cloud.degree)),
        scene(cloud, ctx) {
    stop.resize(size_t(scene.W) * scene.H);
    for (uint32_t y = 0; y < scene.H; ++y)
      for (uint32_t x = 0; x < scene.W; ++x) stop[size_t(y) * scene.W + x] = composite(scene, int(x), int(y)).stop;
  }

  // Sum over all pixels of loss(a) - loss(b), per-pixel differences.
  double full_difference(const Scene& a, const Scene& b, const Context& ca) const {
    const size_t HW = size_t(a.W) * a.H;
    double sum = 0;
    for (uint32_t y = 0; y < a.H; ++y)
      for (uint32_t x = 0; x < a.W; ++x) {
        const size_t pix = size_t(y) * a.W + x;
        sum += pixel_loss(composite(a, int(x), int(y)), pix, HW, ca.bg, v_rgb, v_alpha) -
               pixel_loss(composite(b, int(x), int(y)), pix, HW, ca.bg, v_rgb, v_alpha);
      }
    return sum;
  }

  // The perturbed parameter block of one Gaussian, as a local copy.
  struct Local {
    double mean[3], log_scale[3], quat[4], logit;
    std::vector<double> sh;
    GaussianD view() const { return {mean, log_scale, quat, logit, sh.data()}; }
  };

  Local local_copy(size_t i) const {
    Local L;
    std::copy_n(&cloud.means[i * 3], 3, L.mean);
    std::copy_n(&cloud.log_scales[i * 3], 3, L.log_scale);
    std::copy_n(&cloud.quats[i * 4], 4, L.quat);
    L.logit = cloud.logits[i];
    L.sh.assign(cloud.sh.begin() + i * cloud.coeffs * 3, cloud.sh.begin() + (i + 1) * cloud.coeffs * 3);
    return L;
  }

  void check(Param p, size_t i, int comp) const {
    if (i >= cloud.n) throw std::out_of_range("FiniteDifferences: Gaussian index out of range");
    const int n = p == Param::Mean || p == Param::LogScale ? 3
                  : p == Param::Quat                       ? 4
                  : p == Param::OpacityLogit               ? 1
                                                           : cloud.coeffs * 3;
    if (comp < 0 || comp >= n) throw std::out_of_range("FiniteDifferences: component out of range");
  }

  static double& slot(Local& L, Param p, int comp) {
    switch (p) {
      case Param::Mean:
        return L.mean[comp];
      case Param::LogScale:
        return L.log_scale[comp];
      case Param::Quat:
        return L.quat[comp];
      case Param::OpacityLogit:
        return L.logit;
      case Param::Sh:
        return L.sh[comp];
    }
    throw std::logic_error("bad Param");
  }
  static double& slot(CloudD& c, Param p, size_t i, int comp) {
    switch (p) {
      case Param::Mean:
        return c.means[i * 3 + comp];
      case Param::LogScale:
        return c.log_scales[i * 3 + comp];
      case Param::Quat:
        return c.quats[i * 4 + comp];
      case Param::OpacityLogit:
        return c.logits[i];
      case Param::Sh:
        return c.sh[i * c.coeffs * 3 + comp];
    }
    throw std::logic_error("bad Param");
  }
};

FiniteDifferences::FiniteDifferences(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings,
                                     std::vector<float> v_rgb, std::vector<float> v_alpha) {
  check_weights(cam, v_rgb, v_alpha);
  impl_ = std::make_shared<const Impl>(cloud, cam, settings, std::move(v_rgb), std::move(v_alpha));
}

double FiniteDifferences::param(Param p, size_t gaussian, int component, double h) const {
  const Impl& I = *impl_;
  I.check(p, gaussian, component);
  Impl::Local plus = I.local_copy(gaussian), minus = plus;
  Impl::slot(plus, p, component) += h;
  Impl::slot(minus, p, component) -= h;
  const Proj Pp = project(plus.view(), I.ctx), Pm = project(minus.view(), I.ctx);
  // Only pixels inside a perturbed box can differ between the two evaluations.
  int x0 = INT32_MAX, x1 = -1, y0 = INT32_MAX, y1 = -1;
  for (const Proj* P : {&Pp, &Pm})
    if (P->valid) {
      x0 = std::min(x0, P->x0);
      x1 = std::max(x1, P->x1);
      y0 = std::min(y0, P->y0);
      y1 = std::max(y1, P->y1);
    }
  const size_t HW = size_t(I.scene.W) * I.scene.H;
  const Proj& Pg = I.scene.proj[gaussian];
  double sum = 0;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const size_t pix = size_t(y) * I.scene.W + x;
      // The base render of this pixel stopped at Gaussian st. When the original and both
      // perturbed versions of this Gaussian either miss the pixel or come after st, both
      // evaluations walk the same Gaussians up to st and stop there: the difference is exactly 0.
      // The skipped pixels are exactly those whose two evaluations are bitwise equal.
      // (A Gaussian that does not touch a pixel is a no-op there, wherever it sits in the order.)
      const bool tp = touches(Pp, x, y), tm = touches(Pm, x, y);
      if (!tp && !tm) continue;  // neither evaluation has this Gaussian here: identical
      const uint32_t st = I.stop[pix];
      if (st != UINT32_MAX && st != gaussian) {
        const Proj& S = I.scene.proj[st];
        if ((!touches(Pg, x, y) || before(S, st, Pg, gaussian)) && (!tp || before(S, st, Pp, gaussian)) &&
            (!tm || before(S, st, Pm, gaussian)))
          continue;
      }
      PixelState sp, sm;
      composite_pair(I.scene, x, y, gaussian, Pp, Pm, sp, sm);
      sum +=
          pixel_loss(sp, pix, HW, I.ctx.bg, I.v_rgb, I.v_alpha) - pixel_loss(sm, pix, HW, I.ctx.bg, I.v_rgb, I.v_alpha);
    }
  return sum / (2.0 * h);
}

double FiniteDifferences::param_full_render(Param p, size_t gaussian, int component, double h) const {
  const Impl& I = *impl_;
  I.check(p, gaussian, component);
  CloudD plus = I.cloud, minus = I.cloud;
  Impl::slot(plus, p, gaussian, component) += h;
  Impl::slot(minus, p, gaussian, component) -= h;
  const Scene sp(plus, I.ctx), sm(minus, I.ctx);
  return I.full_difference(sp, sm, I.ctx) / (2.0 * h);
}

std::array<double, 6> FiniteDifferences::pose(double h) const {
  const Impl& I = *impl_;
  std::array<double, 6> g{};
  for (int i = 0; i < 6; ++i) {
    std::array<double, 6> d{};
    d[i] = h;
    const Camera cp = I.cam.perturbed(d);
    d[i] = -h;
    const Camera cm = I.cam.perturbed(d);
    const Context xp = make_context(cp, I.settings, I.cloud.degree), xm = make_context(cm, I.settings, I.cloud.degree);
    const Scene sp(I.cloud, xp), sm(I.cloud, xm);
    g[i] = I.full_difference(sp, sm, xp) / (2.0 * h);
  }
  return g;
}

double FiniteDifferences::loss() const {
  const Impl& I = *impl_;
  const size_t HW = size_t(I.scene.W) * I.scene.H;
  double sum = 0;
  for (uint32_t y = 0; y < I.scene.H; ++y)
    for (uint32_t x = 0; x < I.scene.W; ++x)
      sum +=
          pixel_loss(composite(I.scene, int(x), int(y)), size_t(y) * I.scene.W + x, HW, I.ctx.bg, I.v_rgb, I.v_alpha);
  return sum;
}

int param_components(Param p, const GaussianCloud& cloud) {
  switch (p) {
    case Param::Mean:
    case Param::LogScale:
      return 3;
    case Param::Quat:
      return 4;
    case Param::OpacityLogit:
      return 1;
    case Param::Sh:
      return cloud.coeffs() * 3;
  }
  return 0;
}

RenderOutput render(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings) {
  const CloudD c(cloud);
  const Context ctx = make_context(cam, settings, c.degree);
  const Scene scene(c, ctx);
  return render_scene(scene, ctx);
}

double weighted_loss(const GaussianCloud& cloud, const Camera& cam, const RenderSettings& settings,
                     const std::vector<float>& v_rgb, const std::vector<float>& v_alpha) {
  check_weights(cam, v_rgb, v_alpha);
  const RenderOutput r = render(cloud, cam, settings);
  const size_t HW = size_t(r.width) * r.height;
  double sum = 0;
  for (size_t i = 0; i < 3 * HW; ++i) sum += double(v_rgb[i]) * r.rgb[i];
  for (size_t i = 0; i < HW; ++i) sum += double(v_alpha[i]) * r.alpha[i];
  return sum;
}

}  // namespace evflow::reference
