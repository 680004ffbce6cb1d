#include "train/training_data.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "events/binned_events.h"
#include "events/edi.h"
#include "events/gpu_events.h"
#include "events/warped_events.h"
#include "train/training_flows.h"

namespace evflow {

// Colours for the initial Gaussians: the sharp image when training on it, else the blurry one.
static const io::Image& target_image(const io::View& v, const TrainConfig& cfg) {
  if (cfg.target == TrainTarget::Sharp) {
    if (!v.sharp_mid) throw std::invalid_argument("target=sharp, but view '" + v.name + "' has no sharp image");
    return *v.sharp_mid;
  }
  return v.blurry;
}

std::unique_ptr<IntervalEvents> training_events(gpu::Context& ctx, const io::Dataset& data) {
  const Camera& c0 = data.train.at(0).camera;
  const bool binned = data.events.size() == 0 && !data.event_counts.empty();
  if (data.events.size() == 0 && !binned)
    throw std::invalid_argument("event_weight > 0, but the dataset in '" + data.root + "' has no events");
  if (!binned && (data.events.width != c0.width || data.events.height != c0.height))
    throw std::invalid_argument("the events' sensor (" + std::to_string(data.events.width) + "x" +
                                std::to_string(data.events.height) + ") differs from the images (" +
                                std::to_string(c0.width) + "x" + std::to_string(c0.height) + ")");
  std::vector<EventWindow> windows;
  for (auto& v : data.train) {
    if (!(v.exposure_end > v.exposure_start))
      throw std::invalid_argument("view '" + v.name + "' has no exposure interval for its events");
    windows.push_back({v.exposure_start, v.exposure_end});
  }
  const std::string source = "events of " + data.root;
  if (!binned) return std::make_unique<GpuEvents>(ctx, data.events, windows, source);
  const auto& shape = data.event_counts_shape;
  if (shape.size() != 3 || shape[0] != data.train.size() || shape[2] != size_t(c0.width) * c0.height) {
    std::string dims;
    for (size_t d : shape) dims += (dims.empty() ? "" : ", ") + std::to_string(d);
    throw std::invalid_argument(source + ": binned event counts of shape [" + dims + "] do not fit " +
                                std::to_string(data.train.size()) + " training views of " + std::to_string(c0.width) +
                                "x" + std::to_string(c0.height) + " pixels");
  }
  return std::make_unique<BinnedEvents>(ctx, data.event_counts, uint32_t(shape[1]), c0.width, c0.height, windows,
                                        source);
}

std::pair<double, double> event_thresholds(const io::Dataset& data, const TrainConfig& cfg) {
  double pos = 0.2, neg = 0.2;
  const auto& m = data.manifest;
  if (m.is_object() && m.contains("simulator") && m["simulator"].contains("events")) {
    const auto& e = m["simulator"]["events"];
    if (e.contains("theta_pos") && e["theta_pos"].is_number()) pos = e["theta_pos"].get<double>();
    if (e.contains("theta_neg") && e["theta_neg"].is_number()) neg = e["theta_neg"].get<double>();
  }
  if (m.is_object() && m.contains("event_thresholds") && m["event_thresholds"].is_array() &&
      m["event_thresholds"].size() == 2) {  // a recording's [pos, neg]
    pos = m["event_thresholds"][0].get<double>();
    neg = m["event_thresholds"][1].get<double>();
  }
  if (cfg.event_theta_pos > 0) pos = cfg.event_theta_pos;
  if (cfg.event_theta_neg > 0) neg = cfg.event_theta_neg;
  return {pos, neg};
}

io::Image training_target(const io::Dataset& data, size_t view, const TrainConfig& cfg) {
  if (cfg.target != TrainTarget::Edi) return target_image(data.train.at(view), cfg);
  return edi_frames(data, view, cfg, {0.5}).at(0);
}

std::vector<io::Image> edi_frames(const io::Dataset& data, size_t view, const TrainConfig& cfg,
                                  const std::vector<double>& times) {
  const io::View& v = data.train.at(view);
  if (data.events.size() == 0)
    throw std::invalid_argument("EDI (target=edi, edi_warmup) needs events, and the dataset in '" + data.root +
                                "' has none");
  if (!(v.exposure_end > v.exposure_start))
    throw std::invalid_argument("EDI (target=edi, edi_warmup): view '" + v.name + "' has no exposure interval");
  auto [pos, neg] = event_thresholds(data, cfg);
  const events::EdiIntegrator edi(data.events, v.exposure_start, v.exposure_end,
                                  events::EdiThresholds{pos, neg, {}, {}});
  std::vector<io::Image> out;
  for (double u : times) {
    io::Image frame = v.blurry;
    frame.data = edi.frame_at(v.blurry.data.data(), v.blurry.channels,
                              (1 - u) * v.exposure_start + u * v.exposure_end);  // exact at u = 0, 0.5, 1
    for (float& x : frame.data)
      x = std::isfinite(x) ? std::clamp(x, 0.0f, 1.0f) : 0.0f;  // a training target lives in [0, 1]
    out.push_back(std::move(frame));
  }
  return out;
}

std::vector<float> loss_space_image(const io::Image& image, const TrainConfig& cfg) {
  std::vector<float> planar = io::planar_rgb(image);
  if (cfg.loss_space == LossSpace::Srgb)
    for (float& x : planar) x = io::linear_to_srgb(x);
  return planar;
}

std::vector<float> loss_space_target(const io::Dataset& data, size_t view, const TrainConfig& cfg) {
  return loss_space_image(training_target(data, view, cfg), cfg);
}

std::vector<float> view_warped_event_planes(const io::Dataset& data, const TrainConfig& cfg,
                                            const std::vector<double>& frame_u, size_t v,
                                            const std::vector<std::vector<float>>& flows) {
  const auto [pos, neg] = event_thresholds(data, cfg);
  const io::View& view = data.train.at(v);
  const double t0 = view.exposure_start, span = view.exposure_end - view.exposure_start;
  std::vector<float> planes;
  for (size_t i = 0; i + 1 < frame_u.size(); ++i) {
    const std::vector<float>& d = flows.at(i);
    const std::vector<float> m =
        warp_events_to_end(data.events, t0 + frame_u[i] * span, t0 + frame_u[i + 1] * span, d, pos, neg);
    planes.insert(planes.end(), m.begin(), m.end());
    append_displacement_planes(d, planes);
  }
  return planes;
}

std::vector<std::vector<float>> warped_event_planes(const io::Dataset& data, const TrainConfig& cfg,
                                                    const std::vector<double>& frame_u,
                                                    const std::vector<std::vector<std::vector<float>>>& flows) {
  std::vector<std::vector<float>> out;
  for (size_t v = 0; v < data.train.size(); ++v)
    out.push_back(view_warped_event_planes(data, cfg, frame_u, v, flows.at(v)));
  return out;
}

namespace {

// The mean distance from point i to its 3 nearest other points (brute force).
double neighbour_distance(const std::vector<float>& pts, size_t i) {
  const size_t n = pts.size() / 6;
  double best[3] = {1e300, 1e300, 1e300};
  for (size_t j = 0; j < n; ++j) {
    if (j == i) continue;
    double d = 0;
    for (int k = 0; k < 3; ++k) d += double(pts[j * 6 + k] - pts[i * 6 + k]) * double(pts[j * 6 + k] - pts[i * 6 + k]);
    if (d < best[2]) {
      best[2] = d;
      std::sort(best, best + 3);
    }
  }
  double sum = 0;
  int used = 0;
  for (double b : best)
    if (b < 1e300) sum += std::sqrt(b), ++used;
  return used ? sum / used : 0;
}

// One Gaussian per sparse point: its position and colour, isotropic with the mean distance to its
// 3 nearest neighbours as scale, opacity 0.1.
GaussianCloud points_cloud(const io::Dataset& data, const TrainConfig& cfg) {
  const size_t n = data.points.size() / 6;
  if (n < 4)
    throw std::invalid_argument("init=points: the dataset in '" + data.root +
                                "' has no sparse points (points3D.npy, written by `evflow poses`)");
  GaussianCloud c;
  c.resize(n, cfg.sh_degree);
  const int K = c.coeffs();
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) c.means[i * 3 + k] = data.points[i * 6 + k];
    const float ls = float(std::log(std::max(neighbour_distance(data.points, i), 1e-7)));
    for (int k = 0; k < 3; ++k) c.log_scales[i * 3 + k] = ls;
    c.quats[i * 4] = 1;
    c.quats[i * 4 + 1] = c.quats[i * 4 + 2] = c.quats[i * 4 + 3] = 0;
    c.opacity_logits[i] = float(std::log(0.1 / 0.9));
    for (int ch = 0; ch < 3; ++ch) {
      c.sh[(i * K) * 3 + ch] = float((data.points[i * 6 + 3 + ch] - 0.5) / 0.28209479177387814);
      for (int k = 1; k < K; ++k) c.sh[(i * K + k) * 3 + ch] = 0;
    }
  }
  return c;
}

}  // namespace

GaussianCloud initial_cloud(const io::Dataset& data, const TrainConfig& cfg) {
  if (data.train.empty()) throw std::invalid_argument("dataset has no training views");
  if (cfg.init == InitSource::Points) return points_cloud(data, cfg);
  std::mt19937_64 rng(cfg.seed * 7919 + 17);
  auto uni = [&](double a, double b) { return a + (b - a) * (double(rng() >> 11) * (1.0 / 9007199254740992.0)); };
  const double near = data.near > 0 ? data.near : 0.5, far = data.far > near ? data.far : near * 20;
  GaussianCloud c;
  c.resize(cfg.init_gaussians, cfg.sh_degree);
  const int K = c.coeffs();
  for (size_t i = 0; i < c.size(); ++i) {
    const io::View& v = data.train[rng() % data.train.size()];
    const io::Image& img = target_image(v, cfg);
    const Camera& cam = v.camera;
    const double px = uni(0, cam.width), py = uni(0, cam.height);
    const double z = near * std::pow(far / near, uni(0.05, 0.9));  // log-uniform, away from the bounds
    const double pc[3] = {(px - cam.cx) / cam.fx * z - cam.t[0], (py - cam.cy) / cam.fy * z - cam.t[1], z - cam.t[2]};
    for (int r = 0; r < 3; ++r)
      c.means[i * 3 + r] = float(cam.R[r] * pc[0] + cam.R[3 + r] * pc[1] + cam.R[6 + r] * pc[2]);
    const float ls = float(std::log(1.5 * z / cam.fx));  // ~1.5 px
    for (int k = 0; k < 3; ++k) c.log_scales[i * 3 + k] = ls;
    c.quats[i * 4] = 1;
    c.quats[i * 4 + 1] = c.quats[i * 4 + 2] = c.quats[i * 4 + 3] = 0;
    c.opacity_logits[i] = float(std::log(0.1 / 0.9));
    const uint32_t ix = std::min<uint32_t>(uint32_t(px), img.width - 1),
                   iy = std::min<uint32_t>(uint32_t(py), img.height - 1);
    for (int ch = 0; ch < 3; ++ch) {
      // Splat colours are display-referred sRGB (image_model.h); images are linear in memory.
      const float col = io::linear_to_srgb(
          img.data[(size_t(iy) * img.width + ix) * img.channels + std::min<uint32_t>(ch, img.channels - 1)]);
      c.sh[(i * K) * 3 + ch] = float((col - 0.5) / 0.28209479177387814);
      for (int k = 1; k < K; ++k) c.sh[(i * K + k) * 3 + ch] = 0;
    }
  }
  return c;
}

}  // namespace evflow
