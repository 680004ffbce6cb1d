#include "train/training_flows.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "flow/flow_estimator.h"
#include "io/npy.h"
#include "sim/flow_truth.h"

namespace evflow {

namespace fs = std::filesystem;

namespace {

// FNV-1a, 64 bits.
class Hash64 {
 public:
  void add(const void* data, size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ b[i]) * 0x100000001B3ull;
  }
  template <typename T>
  void add_all(const std::vector<T>& v) {
    add(v.data(), v.size() * sizeof(T));
  }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xCBF29CE484222325ull;
};

void add_options(Hash64& h, const flow::FlowOptions& o) {
  h.add_all(o.tiles), h.add_all(o.image_scale), h.add_all(o.event_stride), h.add_all(o.iterations);
  h.add_all(o.time_groups), h.add_all(o.time_iterations);
  for (double x : {double(o.interval_iterations), double(o.interval_event_stride), o.lr, o.lr_level, o.lr_intervals,
                   o.tv_weight, o.temporal_weight})
    h.add(&x, sizeof x);
}

std::vector<std::vector<float>> estimate_view(flow::FlowEstimator& est, const io::Dataset& data, size_t v,
                                              const std::vector<double>& frame_u) {
  const io::View& view = data.train[v];
  const flow::PixelEvents ev =
      flow::pixel_events(data.events, view.exposure_start, view.exposure_end, data.root + " view " + view.name);
  const flow::ExposureFlow f = est.estimate(ev, frame_u);
  std::vector<std::vector<float>> out;
  for (const auto& interval : f.intervals) out.push_back(flow::dense_flow(interval.grid, f.width, f.height));
  return out;
}

// The cached estimate of view v, or an empty vector when there is none of the right shape.
std::vector<std::vector<float>> read_cache(const fs::path& file, size_t intervals, size_t hw2) {
  if (!fs::exists(file)) return {};
  const io::NpyArray a = io::read_npy(file);
  if (a.shape.size() != 2 || a.shape[0] != intervals || a.shape[1] != hw2) return {};
  const std::vector<float> all = a.as<float>();
  std::vector<std::vector<float>> out;
  for (size_t k = 0; k < intervals; ++k) out.emplace_back(all.begin() + k * hw2, all.begin() + (k + 1) * hw2);
  return out;
}

void write_cache(const fs::path& file, const std::vector<std::vector<float>>& flows) {
  std::vector<float> all;
  for (const auto& f : flows) all.insert(all.end(), f.begin(), f.end());
  try {
    fs::create_directories(file.parent_path());
    io::write_npy<float>(file, {flows.size(), flows.empty() ? 0 : flows[0].size()}, all);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flow: not cached (%s)\n", e.what());  // a read-only dataset still trains
  }
}

std::vector<std::vector<std::vector<float>>> flows_from_events(gpu::Context& ctx, const io::Dataset& data,
                                                               const std::vector<double>& frame_u) {
  if (data.events.size() == 0)
    throw std::invalid_argument("flow=events needs an event stream with times, and the dataset in '" + data.root +
                                "' has none");
  flow::FlowEstimator est(ctx);
  const size_t hw2 = size_t(data.events.width) * data.events.height * 2;
  std::vector<std::vector<std::vector<float>>> out;
  for (size_t v = 0; v < data.train.size(); ++v) {
    const fs::path file = flow_cache_path(data, v, frame_u);
    auto flows = read_cache(file, frame_u.size() - 1, hw2);
    if (flows.empty()) {
      const auto start = std::chrono::steady_clock::now();
      flows = estimate_view(est, data, v, frame_u);
      store_cached_flow(data, v, frame_u, flows);
      std::fprintf(stderr, "flow: view %s estimated in %.1f s\n", data.train[v].name.c_str(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    out.push_back(std::move(flows));
  }
  return out;
}

std::vector<std::vector<std::vector<float>>> flows_from_truth(const io::Dataset& data,
                                                              const std::vector<double>& frame_u) {
  std::vector<std::vector<std::vector<float>>> out;
  for (const io::View& view : data.train) {
    auto truth = sim::ground_truth_interval_flow(data.root, view.name, frame_u);
    if (!truth)
      throw std::invalid_argument("flow=gt needs the simulator's ground truth (gt/trajectories.json and gt/depth/" +
                                  view.name + ".npy), and the dataset in '" + data.root + "' has none");
    out.push_back(std::move(*truth));
  }
  return out;
}

}  // namespace

void append_displacement_planes(const std::vector<float>& d, std::vector<float>& out) {
  const size_t hw = d.size() / 2;
  for (size_t c = 0; c < 2; ++c)
    for (size_t p = 0; p < hw; ++p) out.push_back(std::isfinite(d[2 * p + c]) ? d[2 * p + c] : 0.0f);
}

std::string flow_cache_path(const io::Dataset& data, size_t v, const std::vector<double>& frame_u) {
  const io::View& view = data.train.at(v);
  Hash64 h;
  const char version[] = "evflow-flow-1";
  h.add(version, sizeof version);
  h.add(&data.events.width, sizeof data.events.width), h.add(&data.events.height, sizeof data.events.height);
  h.add_all(frame_u);
  add_options(h, flow::FlowOptions{});
  const auto [first, last] = data.events.window(view.exposure_start, view.exposure_end);
  h.add(data.events.x.data() + first, (last - first) * sizeof(uint16_t));
  h.add(data.events.y.data() + first, (last - first) * sizeof(uint16_t));
  h.add(data.events.t.data() + first, (last - first) * sizeof(double));
  h.add(data.events.p.data() + first, (last - first) * sizeof(int8_t));
  char key[17];
  std::snprintf(key, sizeof key, "%016llx", static_cast<unsigned long long>(h.value()));
  return (fs::path(data.root) / ".evflow-cache" / "flow" / (view.name + "-" + key + ".npy")).string();
}

void store_cached_flow(const io::Dataset& data, size_t view, const std::vector<double>& frame_u,
                       const std::vector<std::vector<float>>& flows) {
  write_cache(flow_cache_path(data, view, frame_u), flows);
}

std::vector<std::vector<std::vector<float>>> training_flows(gpu::Context& ctx, const io::Dataset& data,
                                                            FlowSource source, const std::vector<double>& frame_u) {
  if (frame_u.size() < 2) throw std::invalid_argument("training_flows: fewer than 2 frame times");
  return source == FlowSource::Gt ? flows_from_truth(data, frame_u) : flows_from_events(ctx, data, frame_u);
}

}  // namespace evflow
