// evflow flow DATA --out DIR: optical flow from each training view's events (engine/flow), per
// interval of the virtual frames; with the simulator's ground truth, its endpoint error.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "flow/flow_colour.h"
#include "flow/flow_estimator.h"
#include "flow_images.h"
#include "io/atomic_file.h"
#include "io/dataset.h"
#include "io/image.h"
#include "io/npy.h"
#include "sim/flow_truth.h"
#include "train/train_config.h"
#include "train/training_flows.h"

namespace evflow::app {

namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: evflow flow DATA --out DIR [--view NAME] [--frames F] [--json] [--device N|name]\n"
    "  Optical flow from each training view's events by contrast maximisation, for every interval\n"
    "  between the F virtual frames of its exposure (default 2 * virtual_frames + 1 of the training\n"
    "  defaults). Writes DIR/<view>/flow_<j>.npy (float32 [H, W, 2], pixels over interval j),\n"
    "  flow_<j>.png (colour wheel), iwe_before.png and iwe_after.png (the exposure's events warped\n"
    "  to mid-exposure with zero and with the estimated flow) and DIR/flow.json. With the\n"
    "  simulator's ground truth (gt/), the average endpoint error on pixels with events. Each\n"
    "  estimate also goes into DATA/.evflow-cache/flow/, where training with flow=events and the\n"
    "  same frames finds it.\n"
    "  --json prints {aee_px, contrast_before, contrast_after, iwe_variance_before,\n"
    "  iwe_variance_after, seconds} over the views.\n";

// The IWE at mid-exposure with zero flow and with `flow`, written as PNGs; their variances.
std::pair<double, double> write_iwe(flow::FlowEstimator& est, const flow::ExposureFlow& f, const fs::path& dir) {
  std::vector<flow::FlowGrid> zero;
  for (const auto& i : f.intervals) zero.emplace_back(i.grid.tiles);
  std::vector<flow::FlowGrid> grids;
  for (const auto& i : f.intervals) grids.push_back(i.grid);
  est.evaluate(f.frame_u, zero, {0, 0, 0}, false);
  const std::vector<float> before = est.iwe(1);
  est.evaluate(f.frame_u, grids, {0, 0, 0}, false);
  const std::vector<float> after = est.iwe(1);
  const double scale = std::max(1.0f, *std::max_element(after.begin(), after.end()));
  io::write_png8(dir / "iwe_before.png", f.width, f.height, 1, grey_image(before, scale));
  io::write_png8(dir / "iwe_after.png", f.width, f.height, 1, grey_image(after, scale));
  return {image_variance(before), image_variance(after)};
}

nlohmann::json flow_view(flow::FlowEstimator& est, const io::Dataset& data, size_t v, const std::vector<double>& u,
                         const fs::path& out) {
  const io::View& view = data.train[v];
  const auto start = std::chrono::steady_clock::now();
  const flow::PixelEvents ev =
      flow::pixel_events(data.events, view.exposure_start, view.exposure_end, data.root + " view " + view.name);
  const flow::ExposureFlow f = est.estimate(ev, u);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const fs::path dir = out / view.name;
  fs::create_directories(dir);
  const auto truth = sim::ground_truth_interval_flow(data.root, view.name, u);
  nlohmann::json j = {{"view", view.name}, {"events", ev.size()}, {"contrast_after", f.contrast}, {"seconds", seconds}};
  sim::EndpointError all;
  std::vector<std::vector<float>> dense;
  for (size_t k = 0; k < f.intervals.size(); ++k) {
    const std::vector<float>& d = dense.emplace_back(flow::dense_flow(f.intervals[k].grid, f.width, f.height));
    char name[32];
    std::snprintf(name, sizeof name, "flow_%02zu", k);
    io::write_npy<float>(dir / (std::string(name) + ".npy"), {f.height, f.width, 2}, d);
    io::write_png8(dir / (std::string(name) + ".png"), f.width, f.height, 3, flow::flow_colour_wheel(d, 4.0));
    if (!truth) continue;
    const sim::EndpointError a = sim::endpoint_error(d, (*truth)[k], flow::event_counts(ev, u[k], u[k + 1]));

    j["aee_px"].push_back(a.mean());
    all.sum += a.sum, all.n += a.n;
  }
  if (truth) j["aee_mean_px"] = all.mean(), j["aee_sum"] = all.sum, j["aee_pixels"] = all.n;
  store_cached_flow(data, v, u, dense);  // training with flow=events and these frames reuses it
  const auto [vb, va] = write_iwe(est, f, dir);
  j["iwe_variance_before"] = vb, j["iwe_variance_after"] = va;
  return j;
}

}  // namespace

int run_flow(const Args& args) {
  ArgParser p(args);
  if (p.flag("--help")) {
    std::printf("%s", kUsage);
    return 0;
  }
  const std::string out = p.value("--out"), only = p.value("--view");
  const long long frames = p.integer("--frames", 2 * TrainConfig{}.virtual_frames + 1);
  const bool json = p.flag("--json");
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  const auto pos = p.positional();
  if (pos.size() != 1 || out.empty())
    throw std::invalid_argument(std::string("flow: DATA and --out needed\n") + kUsage);
  if (frames < 2 || frames > 17) throw std::invalid_argument("--frames must be 2..17");
  const io::Dataset data = io::load_dataset(pos[0]);
  if (data.events.size() == 0) throw std::runtime_error(pos[0] + ": no event stream (flow needs events with times)");
  std::vector<double> u;
  for (long long i = 0; i < frames; ++i) u.push_back(double(i) / double(frames - 1));
  gpu::Context ctx(o);
  flow::FlowEstimator est(ctx);
  nlohmann::json views = nlohmann::json::array();
  double aee_sum = 0, seconds = 0, cb = 0, ca = 0, vb = 0, va = 0;
  size_t aee_n = 0;
  for (size_t v = 0; v < data.train.size(); ++v) {
    if (!only.empty() && data.train[v].name != only) continue;
    nlohmann::json j = flow_view(est, data, v, u, out);
    if (!json) std::printf("flow: view %s: %s\n", data.train[v].name.c_str(), j.dump().c_str());
    if (j.contains("aee_sum")) aee_sum += double(j["aee_sum"]), aee_n += size_t(j["aee_pixels"]);
    seconds += double(j["seconds"]), cb += 1, ca += double(j["contrast_after"]);
    vb += double(j["iwe_variance_before"]), va += double(j["iwe_variance_after"]);
    views.push_back(std::move(j));
  }
  if (views.empty()) throw std::invalid_argument("flow: no training view named '" + only + "'");
  const double n = double(views.size());
  nlohmann::json summary = {{"aee_px", aee_n ? nlohmann::json(aee_sum / double(aee_n)) : nlohmann::json(nullptr)},
                            {"contrast_before", cb / n},
                            {"contrast_after", ca / n},
                            {"iwe_variance_before", vb / n},
                            {"iwe_variance_after", va / n},
                            {"seconds", seconds}};
  io::write_file_atomic(fs::path(out) / "flow.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << nlohmann::json{{"summary", summary}, {"frames", frames}, {"views", views}}.dump(1) << "\n";
    if (!f) throw std::runtime_error(tmp.string() + ": write failed");
  });
  std::printf("%s\n", json ? summary.dump().c_str() : ("flow: " + summary.dump()).c_str());
  return 0;
}

static Command reg("flow", "optical flow from each training view's events (contrast maximisation), per interval",
                   run_flow);

}  // namespace evflow::app
