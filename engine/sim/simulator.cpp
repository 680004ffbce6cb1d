#include "sim/simulator.h"

#include "metrics/srgb_metrics.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>

#include "events/edi.h"
#include "io/image.h"

namespace evflow::sim {

namespace fs = std::filesystem;
using Vec3 = std::array<double, 3>;

nlohmann::json SimParams::to_json() const {
  return {{"width", width},
          {"height", height},
          {"fov_y_deg", fov_y_deg},
          {"train_views", train_views},
          {"novel_views", novel_views},
          {"arc_deg", arc_deg},
          {"exposure_s", exposure_s},
          {"view_spacing_s", view_spacing_s},
          {"blur_px", blur_px},
          {"translation_share", translation_share},
          {"shake", shake},
          {"max_step_px", max_step_px},
          {"plan_step_px", plan_step_px},
          {"max_subframes", max_subframes},
          {"pose_noise_rot_deg", pose_noise_rot_deg},
          {"pose_noise_trans", pose_noise_trans},
          {"seed", seed},
          {"events", events.to_json()},
          {"shading",
           {{"light_dir", shading.light_dir},
            {"ambient", shading.ambient},
            {"background", shading.background},
            {"texture_samples", shading.texture_samples}}}};
}

// ---------------------------------------------------------------------------------------------
// Flow and image helpers

namespace {

struct Proj {
  double u, v;
  bool ok;
};

// Camera-frame point of a world point (w = 1) or direction (w = 0).
inline Proj project(const Camera& c, const Vec3& X, bool direction) {
  const double w = direction ? 0.0 : 1.0;
  const double x = c.R[0] * X[0] + c.R[1] * X[1] + c.R[2] * X[2] + w * c.t[0];
  const double y = c.R[3] * X[0] + c.R[4] * X[1] + c.R[5] * X[2] + w * c.t[1];
  const double z = c.R[6] * X[0] + c.R[7] * X[1] + c.R[8] * X[2] + w * c.t[2];
  if (!(z > 1e-9)) return {0, 0, false};
  return {c.fx * x / z + c.cx, c.fy * y / z + c.cy, true};
}

// World point (or direction when depth == 0) seen at pixel centre (x + 0.5, y + 0.5).
inline Vec3 unproject(const Camera& c, double px, double py, double depth, bool& direction) {
  const double dx = (px - c.cx) / c.fx, dy = (py - c.cy) / c.fy;
  direction = !(depth > 0);
  const double z = direction ? 1.0 : depth;
  const double pc[3] = {dx * z - (direction ? 0 : c.t[0]), dy * z - (direction ? 0 : c.t[1]),
                        z - (direction ? 0 : c.t[2])};
  return {c.R[0] * pc[0] + c.R[3] * pc[1] + c.R[6] * pc[2], c.R[1] * pc[0] + c.R[4] * pc[1] + c.R[7] * pc[2],
          c.R[2] * pc[0] + c.R[5] * pc[1] + c.R[8] * pc[2]};
}

struct PointSet {
  std::vector<Vec3> X;
  std::vector<uint8_t> dir;
};

// Surface points of a grid of pixels (every `step` pixels, plus the border) of a frame.
PointSet sample_points(const Frame& f, const Camera& c, uint32_t step) {
  PointSet ps;
  const uint32_t W = f.width, H = f.height;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const bool border = x == 0 || y == 0 || x == W - 1 || y == H - 1;
      if (!border && (x % step || y % step)) continue;
      if (border && (x % 2 || y % 2) && !(x == W - 1 || y == H - 1)) continue;
      bool d;
      ps.X.push_back(unproject(c, x + 0.5, y + 0.5, f.depth[size_t(y) * W + x], d));
      ps.dir.push_back(d);
    }
  return ps;
}

double srgb_byte_roundtrip(float v) {
  const float e = std::round(std::clamp(io::linear_to_srgb(std::clamp(v, 0.f, 1.f)), 0.f, 1.f) * 255.f) / 255.f;
  return io::srgb_to_linear(e);
}

}  // namespace

std::vector<float> ground_truth_flow(const std::vector<float>& depth_a, const Camera& a, const Camera& b) {
  const uint32_t W = a.width, H = a.height;
  if (depth_a.size() != size_t(W) * H)
    throw std::invalid_argument("ground_truth_flow: depth size differs from the camera's");
  std::vector<float> flow(size_t(W) * H * 2);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      bool d;
      const Vec3 X = unproject(a, x + 0.5, y + 0.5, depth_a[i], d);
      const Proj q = project(b, X, d);
      flow[i * 2] = q.ok ? float(q.u - (x + 0.5)) : NAN;
      flow[i * 2 + 1] = q.ok ? float(q.v - (y + 0.5)) : NAN;
    }
  return flow;
}

std::vector<float> warp_by_flow(const std::vector<float>& img, uint32_t W, uint32_t H, uint32_t C,
                                const std::vector<float>& flow) {
  std::vector<float> out(size_t(W) * H * C, 0.f);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t i = size_t(y) * W + x;
      float fx = flow[i * 2], fy = flow[i * 2 + 1];
      if (!std::isfinite(fx) || !std::isfinite(fy)) fx = fy = 0;
      const double sx = std::clamp(x + fx, 0.0f, float(W - 1)), sy = std::clamp(y + fy, 0.0f, float(H - 1));
      const uint32_t x0 = std::min(uint32_t(sx), W - 1), y0 = std::min(uint32_t(sy), H - 1);
      const uint32_t x1 = std::min(x0 + 1, W - 1), y1 = std::min(y0 + 1, H - 1);
      const double ax = sx - x0, ay = sy - y0;
      for (uint32_t c = 0; c < C; ++c) {
        auto at = [&](uint32_t xx, uint32_t yy) { return double(img[(size_t(yy) * W + xx) * C + c]); };
        out[i * C + c] = float((at(x0, y0) * (1 - ax) + at(x1, y0) * ax) * (1 - ay) +
                               (at(x0, y1) * (1 - ax) + at(x1, y1) * ax) * ay);
      }
    }
  return out;
}

double psnr_srgb(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size() || a.empty()) throw std::invalid_argument("psnr_srgb: size mismatch");
  return metrics::psnr(metrics::encode_linear(a, uint32_t(a.size()), 1, 1),
                       metrics::encode_linear(b, uint32_t(b.size()), 1, 1));
}

metrics::Scores scores_srgb(const std::vector<float>& a, const std::vector<float>& b, uint32_t width, uint32_t height) {
  auto planar = [&](const std::vector<float>& hwc) {
    io::Image im(width, height, 3);
    if (hwc.size() != im.data.size()) throw std::invalid_argument("scores_srgb: size mismatch");
    im.data = hwc;
    return metrics::encode_linear(io::planar_rgb(im), width, height, 3);
  };
  return metrics::score(planar(a), planar(b));
}

// ---------------------------------------------------------------------------------------------
// Simulator

Simulator::Simulator(gpu::Context& ctx, const Scene& scene, const SimParams& p)
    : ctx_(ctx), p_(p), renderer_(ctx, scene, p.shading) {
  if (p.width == 0 || p.height == 0 || p.width > 65535 || p.height > 65535)
    throw std::invalid_argument("simulate: bad image size");
  if (p.train_views < 1 || p.novel_views < 0) throw std::invalid_argument("simulate: need at least one training view");
  if (!(p.exposure_s > 0) || !(p.view_spacing_s > p.exposure_s))
    throw std::invalid_argument("simulate: need 0 < exposure_s < view_spacing_s");
  if (!(p.blur_px >= 0) || !(p.max_step_px > 0) || !(p.plan_step_px > 0))
    throw std::invalid_argument("simulate: bad blur/step parameters");
  if (p.shake != "smooth" && p.shake != "jerk")
    throw std::invalid_argument("simulate: shake must be smooth or jerk, not '" + p.shake + "'");
  if (!(p.fov_y_deg > 1 && p.fov_y_deg < 170)) throw std::invalid_argument("simulate: fov_y_deg must be in (1, 170)");
  p_.events.validate();

  // Rig.
  Vec3 target;
  double radius, height;
  if (scene.has_view_hint) {
    target = {scene.view_target[0], scene.view_target[1], scene.view_target[2]};
    radius = scene.view_radius;
    height = scene.view_height;
  } else {
    const auto lo = scene.bounds_min(), hi = scene.bounds_max();
    double half = 0;
    for (int i = 0; i < 3; ++i) {
      target[i] = 0.5 * (lo[i] + hi[i]);
      half += 0.25 * double(hi[i] - lo[i]) * (hi[i] - lo[i]);
    }
    half = std::max(std::sqrt(half), 1e-6);
    radius = 1.15 * half / std::sin(0.5 * p.fov_y_deg * M_PI / 180.0);
    height = 0.25 * radius;
  }
  target_dist_ = std::hypot(radius, height);
  const double arc = p.arc_deg * M_PI / 180.0;
  auto eye_at = [&](double a, double r, double h) {
    return Vec3{target[0] + r * std::sin(a), target[1] + h, target[2] + r * std::cos(a)};
  };
  for (int i = 0; i < p.train_views; ++i) {
    const double f = p.train_views > 1 ? double(i) / (p.train_views - 1) : 0.5;
    const double a = -0.5 * arc + arc * f;
    const double h = height * (1.0 + 0.15 * std::sin(2.3 * i));
    Vec3 look = {target[0] + 0.05 * radius * std::sin(1.7 * i), target[1], target[2]};
    Camera c = Camera::look_at(p.width, p.height, p.fov_y_deg, eye_at(a, radius, h), look);
    c.near_plane = 1e-3 * radius;
    train_.push_back(c);
  }
  for (int j = 0; j < p.novel_views; ++j) {
    const double f = (j + 0.5) / std::max(1, p.novel_views);
    const double a = -0.5 * arc + arc * f;
    const double r = radius * (0.92 + 0.12 * ((j % 3) / 2.0));
    const double h = height * (0.8 + 0.3 * ((j * 7 % 5) / 4.0));
    Camera c = Camera::look_at(p.width, p.height, p.fov_y_deg, eye_at(a, r, h), target);
    c.near_plane = 1e-3 * radius;
    novel_.push_back(c);
  }
  // Shake: per view and degree of freedom, 3 sinusoids with random amplitude, frequency, phase.
  std::mt19937_64 g(p.seed * 0x9E3779B97F4A7C15ull + 12345);
  for (int v = 0; v < p.train_views; ++v) {
    std::array<double, 54> s{};
    for (int d = 0; d < 6; ++d)
      for (int k = 0; k < 3; ++k) {
        double* t = &s[(d * 3 + k) * 3];
        t[0] = events::normal01(g) / (k + 1);
        t[1] = 0.25 + 1.0 * events::uniform01(g);
        t[2] = 2 * M_PI * events::uniform01(g);
      }
    shake_terms_.push_back(s);
  }
  // Jerks from a stream of their own: the smooth shake stays what it was.
  std::mt19937_64 gj(p.seed * 0xD1B54A32D192ED03ull + 777);
  for (int v = 0; v < p.train_views && p.shake == "jerk"; ++v) {
    std::array<double, 12> j{};
    for (int d = 0; d < 6; ++d) {
      j[d * 2] = 6.0 * events::normal01(gj);
      j[d * 2 + 1] = 0.2 + 0.6 * events::uniform01(gj);
    }
    jerk_terms_.push_back(j);
  }
}

namespace {
// A velocity step of size a at s0, 0.01 wide: a * w * softplus((s - s0) / w).
double jerk(double a, double s0, double s) {
  const double w = 0.01, z = (s - s0) / w;
  return a * w * (z > 30 ? z : std::log1p(std::exp(z)));
}
}  // namespace

Camera Simulator::shake_pose(int v, double s, double scale) const {
  const auto& st = shake_terms_.at(v);
  std::array<double, 6> delta{};
  for (int d = 0; d < 6; ++d) {
    // Translation (d < 3) in scene units relative to the viewing distance; roll (d = 5) smaller.
    const double w = d < 3 ? p_.translation_share * target_dist_ * 0.01 : (d == 5 ? 0.5 : 1.0) * 0.01;
    double sum = 0;
    for (int k = 0; k < 3; ++k) {
      const double* t = &st[(d * 3 + k) * 3];
      sum += t[0] * (std::sin(2 * M_PI * t[1] * s + t[2]) - std::sin(2 * M_PI * t[1] * 0.5 + t[2]));
    }
    if (!jerk_terms_.empty()) {
      const double* j = &jerk_terms_.at(v)[d * 2];
      sum += jerk(j[0], j[1], s) - jerk(j[0], j[1], 0.5);
    }
    delta[d] = scale * w * sum;
  }
  if (s == 0.5 || scale == 0) return train_.at(v);
  return train_.at(v).perturbed(delta);
}

double Simulator::calibrate_shake(int v, const Frame& mid) const {
  if (p_.blur_px <= 0) return 0;
  const PointSet ps = sample_points(mid, train_[v], 4);
  auto path_length = [&](double scale) {
    const int steps = 128;
    std::vector<Proj> prev(ps.X.size());
    std::vector<double> len(ps.X.size(), 0);
    std::vector<uint8_t> ok(ps.X.size(), 1);
    for (int i = 0; i <= steps; ++i) {
      const Camera c = shake_pose(v, double(i) / steps, scale);
      for (size_t j = 0; j < ps.X.size(); ++j) {
        const Proj q = project(c, ps.X[j], ps.dir[j]);
        if (!q.ok) ok[j] = 0;
        if (i > 0 && q.ok && prev[j].ok) len[j] += std::hypot(q.u - prev[j].u, q.v - prev[j].v);
        prev[j] = q;
      }
    }
    double s = 0;
    size_t n = 0;
    for (size_t j = 0; j < len.size(); ++j)
      if (ok[j]) {
        s += len[j];
        ++n;
      }
    return n ? s / n : 0.0;
  };
  const double probe = 1e-2;
  const double l1 = path_length(probe);
  if (!(l1 > 0)) return 0;
  double scale = p_.blur_px * probe / l1;
  const double l2 = path_length(scale);
  if (l2 > 0) scale *= p_.blur_px / l2;
  return scale;
}

std::vector<double> Simulator::plan_subframes(int v, const Frame& mid, double scale) const {
  if (scale == 0) return {0.0, 0.5, 1.0};
  const PointSet ps = sample_points(mid, train_[v], 4);
  const int fine = 1024;
  auto proj_all = [&](double s) {
    const Camera c = shake_pose(v, s, scale);
    std::vector<Proj> q(ps.X.size());
    for (size_t j = 0; j < q.size(); ++j) q[j] = project(c, ps.X[j], ps.dir[j]);
    return q;
  };
  auto max_motion = [](const std::vector<Proj>& a, const std::vector<Proj>& b) {
    double m = 0;
    for (size_t j = 0; j < a.size(); ++j)
      if (a[j].ok && b[j].ok) m = std::max(m, std::hypot(a[j].u - b[j].u, a[j].v - b[j].v));
    return m;
  };
  std::vector<double> samples{0.0};
  std::vector<Proj> last = proj_all(0.0), prev = last;
  int last_i = 0;
  for (int i = 1; i <= fine; ++i) {
    std::vector<Proj> cur = proj_all(double(i) / fine);
    if (max_motion(last, cur) > p_.plan_step_px && i - 1 > last_i) {
      samples.push_back(double(i - 1) / fine);
      last = prev;
      last_i = i - 1;
    }
    if (i == fine / 2 || i == fine) {
      if (last_i != i) samples.push_back(double(i) / fine);
      last = cur;
      last_i = i;
    }
    prev = std::move(cur);
    if (int(samples.size()) > p_.max_subframes)
      throw std::runtime_error("simulate: view " + std::to_string(v) + " needs more than " +
                               std::to_string(p_.max_subframes) + " sub-frames (blur too large?)");
  }
  return samples;
}

TrainViewResult Simulator::simulate_view(int v, events::EventSimulator& ev, const IntervalCallback& cb) {
  TrainViewResult r;
  char name[32];
  std::snprintf(name, sizeof name, "%03d", v);
  r.name = name;
  r.gt_camera = train_.at(v);
  r.t0 = v * p_.view_spacing_s;
  r.t1 = r.t0 + p_.exposure_s;
  const size_t P = size_t(p_.width) * p_.height;
  r.sharp_mid = renderer_.render(r.gt_camera);
  r.shake_scale = calibrate_shake(v, r.sharp_mid);
  std::vector<double> s = plan_subframes(v, r.sharp_mid, r.shake_scale);
  auto time_of = [&](double f) { return f >= 1.0 ? r.t1 : r.t0 + f * (r.t1 - r.t0); };

  Camera cam_prev = shake_pose(v, s[0], r.shake_scale);
  Frame prev = s[0] == 0.5 ? r.sharp_mid : renderer_.render(cam_prev);
  ev.add_frame_rgb(prev.rgb.data(), time_of(s[0]));
  r.times.push_back(time_of(s[0]));
  r.poses.push_back(cam_prev);
  std::vector<double> acc(P * 3, 0.0);
  size_t i = 1;
  int k = 0;
  while (i < s.size()) {
    const Camera cam = shake_pose(v, s[i], r.shake_scale);
    std::vector<float> flow = ground_truth_flow(prev.depth, cam_prev, cam);
    double maxm = 0, summ = 0;
    size_t n = 0;
    for (size_t j = 0; j < P; ++j) {
      const double m = std::hypot(flow[j * 2], flow[j * 2 + 1]);
      if (std::isfinite(m)) {
        maxm = std::max(maxm, m);
        summ += m;
        ++n;
      }
    }
    if (maxm > p_.max_step_px && s[i] - s[i - 1] > 1e-7) {
      s.insert(s.begin() + i, 0.5 * (s[i - 1] + s[i]));
      if (int(s.size()) > p_.max_subframes)
        throw std::runtime_error("simulate: view " + std::to_string(v) + " needs more than " +
                                 std::to_string(p_.max_subframes) + " sub-frames");
      continue;
    }
    Frame cur = s[i] == 0.5 ? r.sharp_mid : renderer_.render(cam);
    const double w = 0.5 * (s[i] - s[i - 1]);
    for (size_t j = 0; j < P * 3; ++j) acc[j] += w * (double(prev.rgb[j]) + cur.rgb[j]);
    ev.add_frame_rgb(cur.rgb.data(), time_of(s[i]));
    r.mean_blur_px += n ? summ / n : 0.0;
    r.max_step_px = std::max(r.max_step_px, maxm);
    if (s[i - 1] == 0.5) r.mid_flow = flow;
    if (cb) cb(Interval{v, k, s[i - 1], s[i], time_of(s[i - 1]), time_of(s[i]), prev, cur, cam_prev, cam, flow, maxm});
    r.times.push_back(time_of(s[i]));
    r.poses.push_back(cam);
    prev = std::move(cur);
    cam_prev = cam;
    ++i;
    ++k;
  }
  r.blurry.resize(P * 3);
  for (size_t j = 0; j < P * 3; ++j) r.blurry[j] = float(acc[j]);
  return r;
}

SimResult Simulator::run(const IntervalCallback& cb, bool verbose) {
  const auto start = std::chrono::steady_clock::now();
  SimResult res;
  res.params = p_;
  res.events.width = p_.width;
  res.events.height = p_.height;
  double near = INFINITY, far = 0;
  auto bounds = [&](const Frame& f) {
    for (float d : f.depth)
      if (d > 0) {
        near = std::min(near, double(d));
        far = std::max(far, double(d));
      }
  };
  for (int v = 0; v < p_.train_views; ++v) {
    events::EventSimulator ev(p_.width, p_.height, p_.events, p_.seed + uint64_t(v));
    TrainViewResult r = simulate_view(v, ev, cb);
    EventStream es = ev.take_events();
    auto& E = res.events;
    E.x.insert(E.x.end(), es.x.begin(), es.x.end());
    E.y.insert(E.y.end(), es.y.begin(), es.y.end());
    E.t.insert(E.t.end(), es.t.begin(), es.t.end());
    E.p.insert(E.p.end(), es.p.begin(), es.p.end());
    bounds(r.sharp_mid);
    res.stats.subframes += r.times.size();
    res.stats.mean_blur_px += r.mean_blur_px / p_.train_views;
    res.stats.max_step_px = std::max(res.stats.max_step_px, r.max_step_px);
    if (verbose)
      std::printf("  view %s: %zu sub-frames, blur %.2f px, max step %.3f px, %zu events\n", r.name.c_str(),
                  r.times.size(), r.mean_blur_px, r.max_step_px, es.size());
    // Recorded pose: ground truth with pose noise.
    std::mt19937_64 g(p_.seed * 0xD1B54A32D192ED03ull + 777 + v);
    std::array<double, 6> noise{};
    for (int d = 0; d < 6; ++d)
      noise[d] = events::normal01(g) * (d < 3 ? p_.pose_noise_trans : p_.pose_noise_rot_deg * M_PI / 180.0);
    r.recorded_camera =
        (p_.pose_noise_trans > 0 || p_.pose_noise_rot_deg > 0) ? r.gt_camera.perturbed(noise) : r.gt_camera;
    res.train.push_back(std::move(r));
  }
  for (int j = 0; j < p_.novel_views; ++j) {
    NovelViewResult nv;
    char name[32];
    std::snprintf(name, sizeof name, "novel_%03d", j);
    nv.name = name;
    nv.camera = novel_[j];
    nv.frame = renderer_.render(nv.camera);
    bounds(nv.frame);
    res.novel.push_back(std::move(nv));
  }
  if (!(near < INFINITY)) {
    near = 0.01;
    far = 100;
  }
  res.near = 0.9 * near;
  res.far = 1.1 * far;
  res.events.validate("simulate");
  // EDI check with the nominal thresholds on the 8-bit blurry images.
  events::EdiThresholds th;
  th.pos = p_.events.theta_pos;
  th.neg = p_.events.theta_neg;
  for (auto& r : res.train) {
    std::vector<float> bq(r.blurry.size());
    for (size_t j = 0; j < bq.size(); ++j) bq[j] = float(srgb_byte_roundtrip(r.blurry[j]));
    const auto edi = events::edi_deblur(bq.data(), 3, res.events, r.t0, r.t1, th);
    const auto sb = scores_srgb(bq, r.sharp_mid.rgb, p_.width, p_.height),
               se = scores_srgb(edi, r.sharp_mid.rgb, p_.width, p_.height);
    res.stats.psnr_blurry += sb.psnr / res.train.size();
    res.stats.psnr_edi += se.psnr / res.train.size();
    res.stats.ssim_blurry += sb.ssim / res.train.size();
    res.stats.ssim_edi += se.ssim / res.train.size();
  }
  res.stats.events = res.events.size();
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace evflow::sim
