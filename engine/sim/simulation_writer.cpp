#include "sim/simulation_writer.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "io/atomic_file.h"
#include "io/dataset_writer.h"
#include "io/image.h"
#include "io/npy.h"

namespace evflow::sim {

namespace fs = std::filesystem;

namespace {

nlohmann::json camera_json(const Camera& c) {
  return {{"R", c.R}, {"t", c.t}, {"intrinsics", {c.fx, c.fy, c.cx, c.cy}}, {"size", {c.width, c.height}}};
}

io::Dataset to_dataset(const SimResult& res) {
  io::Dataset d;
  d.layout = "evflow";
  const uint32_t W = res.params.width, H = res.params.height;
  for (auto& r : res.train) {
    io::View v;
    v.name = r.name;
    v.blurry = io::Image(W, H, 3);
    v.blurry.data = r.blurry;
    v.camera = r.recorded_camera;
    v.exposure_start = r.t0;
    v.exposure_end = r.t1;
    io::Image sharp(W, H, 3);
    sharp.data = r.sharp_mid.rgb;
    v.sharp_mid = std::move(sharp);
    d.train.push_back(std::move(v));
  }
  for (auto& n : res.novel) {
    io::View v;
    v.name = n.name;
    v.camera = n.camera;
    io::Image sharp(W, H, 3);
    sharp.data = n.frame.rgb;
    v.sharp_mid = std::move(sharp);
    d.novel.push_back(std::move(v));
  }
  d.events = res.events;
  d.near = res.near;
  d.far = res.far;
  nlohmann::json sim = res.params.to_json();
  sim["scene"] = res.scene_source;
  sim["statistics"] = {{"seconds", res.stats.seconds},         {"events", res.stats.events},
                       {"subframes", res.stats.subframes},     {"mean_blur_px", res.stats.mean_blur_px},
                       {"max_step_px", res.stats.max_step_px}, {"psnr_blurry_db", res.stats.psnr_blurry},
                       {"psnr_edi_db", res.stats.psnr_edi},    {"ssim_blurry", res.stats.ssim_blurry},
                       {"ssim_edi", res.stats.ssim_edi}};
  sim["ground_truth"] = {{"trajectories", "gt/trajectories.json"},
                         {"depth", "gt/depth/<view>.npy"},
                         {"flow_mid", "gt/flow/<view>_mid.npy"}};
  d.manifest["simulator"] = sim;
  return d;
}

}  // namespace

void write_simulation(const SimResult& res, const fs::path& dir) {
  fs::create_directories(dir / "gt" / "depth");
  fs::create_directories(dir / "gt" / "flow");
  const size_t W = res.params.width, H = res.params.height;
  nlohmann::json traj = nlohmann::json::array();
  for (auto& r : res.train) {
    nlohmann::json sub = nlohmann::json::array();
    for (size_t i = 0; i < r.times.size(); ++i)
      sub.push_back({{"t", r.times[i]}, {"R", r.poses[i].R}, {"T", r.poses[i].t}});
    traj.push_back({{"name", r.name},
                    {"exposure", {r.t0, r.t1}},
                    {"gt_camera", camera_json(r.gt_camera)},
                    {"recorded_camera", camera_json(r.recorded_camera)},
                    {"mean_blur_px", r.mean_blur_px},
                    {"max_step_px", r.max_step_px},
                    {"subframes", sub}});
    io::write_npy<float>(dir / "gt" / "depth" / (r.name + ".npy"), {H, W}, r.sharp_mid.depth);
    if (!r.mid_flow.empty()) io::write_npy<float>(dir / "gt" / "flow" / (r.name + "_mid.npy"), {H, W, 2}, r.mid_flow);
  }
  for (auto& n : res.novel) io::write_npy<float>(dir / "gt" / "depth" / (n.name + ".npy"), {H, W}, n.frame.depth);
  nlohmann::json j = {{"convention", "world_to_camera p_c = R p_w + T, OpenCV axes; times in seconds"},
                      {"train", traj}};
  io::write_file_atomic(dir / "gt" / "trajectories.json", [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << j.dump(1) << "\n";
    io::close_or_throw(f, dir / "gt" / "trajectories.json");
  });
  io::write_evflow_dataset(to_dataset(res), dir);
}

}  // namespace evflow::sim
