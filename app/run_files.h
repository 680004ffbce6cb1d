// What a training run folder holds and how the commands that read it load it.
#pragma once
#include <filesystem>
#include <fstream>

#include "io/dataset.h"
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
    if (!f) throw std::runtime_error((dir / "config.json").string() + ": missing (is '" + dir.string() + "' a training run?)");
    try { f >> r.config; } catch (const std::exception& e) { throw std::runtime_error((dir / "config.json").string() + ": " + e.what()); }
    // Runs from before splat colours became sRGB hold linear colours: they would render too dark.
    if (!r.config.is_object() || !r.config.contains("loss_space"))
      throw std::runtime_error((dir / "config.json").string() +
                               ": a run from before EvFlow's splat colours became sRGB (no loss_space); retrain it");
    r.checkpoint = read_checkpoint(dir / "checkpoint.ckpt");
    return r;
  }
  std::string data_dir() const { return config.value("data", std::string()); }
};

}  // namespace evflow::app
