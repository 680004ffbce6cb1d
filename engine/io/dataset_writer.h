// The writer of our dataset layout (dataset.json, images, events, poses); docs/datasets.md.
#pragma once
#include <filesystem>
#include <string>

#include "io/dataset.h"

namespace evflow::io {

struct WriteOptions {
  std::string image_ext = ".png";  // ".png" (8-bit sRGB) or ".exr" (float, exact)
};

// Writes our layout into `dir` (created if needed), every file atomically, dataset.json last.
// Throws std::invalid_argument on inconsistent input (image sizes, missing images, bad names).
void write_evflow_dataset(const Dataset& dataset, const std::filesystem::path& dir, const WriteOptions& options = {});

}  // namespace evflow::io
