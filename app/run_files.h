// What a training run folder holds and how the commands that read it load it.
#pragma once
#include <filesystem>
#include <fstream>

#include "camera/trajectory.h"
#include "io/dataset.h"
#include "io/gltf_splats.h"
#include "io/ply_splats.h"
#include "train/checkpoint.h"
#include "train/train_config.h"

namespace evflow::app {

struct RunFolder {
  std::filesystem::path dir;
  nlohmann::json config;  // config.json: the TrainConfig plus "data"
  Checkpoint checkpoint;

  static RunFolder open(const std::filesystem::path& dir) {
    RunFolder r;
    r.dir = dir;
    std::ifstream f(dir / "config.json");
    if (!f)
      throw std::runtime_error((dir / "config.json").string() + ": missing (is '" + dir.string() +
                               "' a training run?)");
    try {
      f >> r.config;
    } catch (const std::exception& e) { throw std::runtime_error((dir / "config.json").string() + ": " + e.what()); }
    // Runs from before splat colours became sRGB hold linear colours: they would render too dark.
    if (!r.config.is_object() || !r.config.contains("loss_space"))
      throw std::runtime_error((dir / "config.json").string() +
                               ": a run from before EvFlow's splat colours became sRGB (no loss_space); retrain it");
    r.checkpoint = read_checkpoint(dir / "checkpoint.ckpt");
    return r;
  }
  std::string data_dir() const { return config.value("data", std::string()); }
  // Training view `index`'s learned camera at exposure time u: its trajectory's pose (blur
  // mode), its refined pose (pose_refine, any u) or, without either, the dataset's.
  Camera learned_camera(const io::View& v, size_t index, double u) const {
    const auto& trajs = checkpoint.trajectories;
    if (trajs.empty()) return v.camera;
    if (index >= trajs.size())
      throw std::runtime_error(dir.string() + ": the checkpoint has " + std::to_string(trajs.size()) +
                               " learned cameras, not one for training view " + std::to_string(index));
    if (trajs[index].knots.size() == 6) {
      std::array<double, 6> d;
      std::copy(trajs[index].knots.begin(), trajs[index].knots.end(), d.begin());
      return v.camera.perturbed(d);
    }
    ExposureTrajectory t(v.camera, 0, 0.0);
    std::copy(trajs[index].knots.begin(), trajs[index].knots.end(), t.data());
    return t.camera_at(u);
  }
};

// Splats from a run folder (its checkpoint), a .ply or a .glb/.gltf.
inline GaussianCloud load_splats(const std::filesystem::path& src) {
  if (std::filesystem::is_directory(src)) return RunFolder::open(src).checkpoint.cloud;
  if (src.extension() == ".ply") return io::read_ply(src);
  return io::read_gltf_splats(src);
}

}  // namespace evflow::app
