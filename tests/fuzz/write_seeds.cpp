// Writes the harnesses' seed corpora (tests/fuzz/corpus/<harness>/) with EvFlow's own writers:
// small valid files of every kind the readers take. `scripts/fuzz.sh --seeds` runs it.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fuzz_dataset_base.h"
#include "io/events_h5.h"
#include "io/events_txt.h"
#include "io/gltf_splats.h"
#include "io/llff.h"
#include "io/npy.h"
#include "io/ply_splats.h"
#include "nn/safetensors.h"
#include "sim/gltf_scene.h"
#include "train/checkpoint.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Writes `prefix` (the harness's option byte, if any) followed by the file at `from`.
void seed(const fs::path& corpus, const std::string& name, const fs::path& from, const std::string& prefix = "") {
  fs::create_directories(corpus);
  std::ofstream(corpus / name, std::ios::binary) << prefix << slurp(from);
}

GaussianCloud cloud(size_t n, int degree) {
  GaussianCloud c;
  c.resize(n, degree);
  for (size_t i = 0; i < c.means.size(); ++i) c.means[i] = 0.1f * float(i % 7) - 0.3f;
  for (size_t i = 0; i < c.log_scales.size(); ++i) c.log_scales[i] = -2.0f + 0.05f * float(i % 5);
  for (size_t i = 0; i < n; ++i) c.quats[i * 4] = 1.0f;
  for (size_t i = 0; i < n; ++i) c.opacity_logits[i] = 0.5f;
  for (size_t i = 0; i < c.sh.size(); ++i) c.sh[i] = 0.02f * float(i % 11);
  return c;
}

sim::Scene triangle_scene() {
  sim::Scene s;
  s.source = "seed";
  s.materials.push_back({"red", {0.8f, 0.2f, 0.1f, 1.0f}, -1});
  s.add_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, 0);
  return s;
}

EventStream events() { return fuzz::tiny_dataset().events; }

void write_all(const fs::path& out, const fs::path& tmp) {
  for (int d : {0, 1, 3}) {
    const std::string n = "deg" + std::to_string(d);
    io::write_ply(tmp / (n + ".ply"), cloud(3, d));
    seed(out / "ply", n + ".ply", tmp / (n + ".ply"));
    io::write_gltf_splats(tmp / (n + ".glb"), cloud(3, d));
    seed(out / "gltf_splats", n + ".glb", tmp / (n + ".glb"));
  }
  io::write_gltf_splats(tmp / "deg1.gltf", cloud(2, 1));
  seed(out / "gltf_splats", "deg1.gltf", tmp / "deg1.gltf");
  sim::write_gltf(triangle_scene(), tmp / "quad.glb");
  sim::write_gltf(triangle_scene(), tmp / "quad.gltf");
  seed(out / "gltf_scene", "quad.glb", tmp / "quad.glb");
  seed(out / "gltf_scene", "quad.gltf", tmp / "quad.gltf");
  io::write_npy<float>(tmp / "f4.npy", {2, 3}, {1, 2, 3, 4, 5, 6});
  io::write_npy<int16_t>(tmp / "i2.npy", {4}, {-1, 0, 1, 2});
  io::write_npy<bool>(tmp / "b1.npy", {2}, std::vector<bool>{true, false});
  for (const char* n : {"f4.npy", "i2.npy", "b1.npy"}) seed(out / "npy", n, tmp / n);
  io::write_events_h5(tmp / "ev.h5", events(), {0.0}, {0.05}, {.t_offset_us = 1000, .deflate_level = 0});
  seed(out / "h5_events", "us_offset.h5", tmp / "ev.h5", std::string(1, char(2 | 4)));
  io::write_events_h5(tmp / "evz.h5", events(), {}, {}, {.t_offset_us = 0, .deflate_level = 1});
  seed(out / "h5_events", "us_deflate.h5", tmp / "evz.h5", std::string(1, char(2)));
  io::write_events_txt(tmp / "ev.txt", events());
  seed(out / "txt_events", "s_01.txt", tmp / "ev.txt", std::string(1, char(0)));
  io::write_events_txt(tmp / "ev_us.txt", events(), {io::TimeUnit::us, io::PolarityCoding::minus_one_one, false});
  seed(out / "txt_events", "us_pm1.txt", tmp / "ev_us.txt", std::string(1, char(2 | 1 << 2)));
}

void write_dataset_and_checkpoint(const fs::path& out, const fs::path& tmp) {
  const io::Dataset ds = fuzz::tiny_dataset();
  io::write_evflow_dataset(ds, tmp / "ds");
  seed(out / "dataset", "evflow.json", tmp / "ds" / "dataset.json", std::string(1, char(0)));
  std::ofstream(tmp / "transforms.json")
      << R"({"camera_angle_x": 0.69, "frames": [{"file_path": "./train/000", "transform_matrix": )"
      << R"([[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}, {"file_path": "./train/001.png", "transform_matrix": )"
      << R"([[1,0,0,1],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}]})";
  seed(out / "dataset", "nerf.json", tmp / "transforms.json", std::string(1, char(1)));
  std::vector<Camera> cams;
  for (auto& v : ds.train) cams.push_back(v.camera);
  io::write_poses_bounds(tmp / "pb.npy", cams, {1, 1, 1}, {8, 8, 8});
  seed(out / "dataset", "llff.npy", tmp / "pb.npy", std::string(1, char(2)));
  Checkpoint c;
  c.step = 7;
  c.cloud = cloud(3, 1);
  c.optimizer.push_back({"means", 7, std::vector<float>(9, 0.5f), std::vector<float>(9, 0.25f)});
  c.trajectories.push_back({7, std::vector<double>(6, 0.01), std::vector<double>(6, 0), std::vector<double>(6, 1)});
  c.trajectories.push_back(c.trajectories[0]);  // and one whose mid-exposure pose has its own Adam
  c.trajectories[1].mid_step = 3;
  c.trajectories[1].mid_exp_avg = c.trajectories[1].mid_exp_avg_sq = std::vector<double>(6, 0.5);
  write_checkpoint(tmp / "c.ckpt", c);
  seed(out / "checkpoint", "blur_pose.ckpt", tmp / "c.ckpt");
}

// Weights as a conv stack saves them (two layers and metadata), and a file with no tensors.
void write_safetensors(const fs::path& out, const fs::path& tmp) {
  nn::SafetensorsFile f;
  f.metadata["format"] = "evflow";
  f.tensors.push_back({"ldi.0.weight", {2, 1, 3, 3}, std::vector<float>(18, 0.125f)});
  f.tensors.push_back({"ldi.0.bias", {2}, {0.5f, -1.0f}});
  f.tensors.push_back({"ldi.1.weight", {1, 2, 1, 1}, {1.0f, -2.0f}});
  f.tensors.push_back({"ldi.1.bias", {1}, {0.0f}});
  nn::save_safetensors(tmp / "w.safetensors", f);
  seed(out / "safetensors", "ldi.safetensors", tmp / "w.safetensors");
  nn::save_safetensors(tmp / "e.safetensors", nn::SafetensorsFile{});
  seed(out / "safetensors", "empty.safetensors", tmp / "e.safetensors");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_seeds CORPUS_DIR\n");
    return 2;
  }
  const fs::path out = argv[1], tmp = fuzz::work_dir() / "seeds";
  try {
    write_all(out, tmp);
    write_dataset_and_checkpoint(out, tmp);
    write_safetensors(out, tmp);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "write_seeds: %s\n", e.what());
    return 1;
  }
  fs::remove_all(fuzz::work_dir());
  return 0;
}
