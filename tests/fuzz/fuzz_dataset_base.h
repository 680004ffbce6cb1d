// The dataset folders the dataset harness fuzzes the manifests of: a small valid dataset in our
// layout, and the images of one in the NeRF-synthetic and the LLFF layouts (their manifests,
// transforms_train.json and poses_bounds.npy, come from the fuzzer).
#pragma once
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "fuzz_input.h"
#include "io/dataset.h"
#include "io/dataset_writer.h"
#include "io/image.h"

namespace evflow::fuzz {

struct DatasetFolders {
  // Each layout's folder and the manifest's file name in it.
  std::vector<std::pair<std::filesystem::path, std::string>> layouts;
};

inline io::Dataset tiny_dataset() {
  io::Dataset ds;
  ds.layout = "evflow";
  for (int i = 0; i < 3; ++i) {
    io::View v;
    v.name = "00" + std::to_string(i);
    v.blurry = io::Image(4, 3, 3, 0.25f * float(i + 1));
    v.camera = Camera::look_at(4, 3, 60.0, {double(i), 0, 4}, {0, 0, 0}, {0, -1, 0});
    v.exposure_start = 0.1 * i;
    v.exposure_end = 0.1 * i + 0.05;
    ds.train.push_back(v);
  }
  for (int i = 0; i < 4; ++i) {
    ds.events.x.push_back(uint16_t(i % 4));
    ds.events.y.push_back(uint16_t(i % 3));
    ds.events.t.push_back(0.01 * i);
    ds.events.p.push_back(i % 2 ? 1 : -1);
  }
  ds.events.width = 4;
  ds.events.height = 3;
  ds.near = 1;
  ds.far = 8;
  return ds;
}

inline DatasetFolders make_dataset_folders() {
  namespace fs = std::filesystem;
  DatasetFolders f;
  const fs::path ours = work_dir() / "evflow", nerf = work_dir() / "nerf", llff = work_dir() / "llff";
  io::write_evflow_dataset(tiny_dataset(), ours);
  for (const fs::path& d : {nerf / "train", llff / "images"}) {
    fs::create_directories(d);
    for (const char* n : {"000.png", "001.png", "002.png"}) fs::copy_file(ours / "images" / n, d / n);
  }
  f.layouts = {{ours, "dataset.json"}, {nerf, "transforms_train.json"}, {llff, "poses_bounds.npy"}};
  return f;
}

}  // namespace evflow::fuzz
