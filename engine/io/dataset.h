// Multi-view datasets in memory and the reader of whole dataset folders: load_dataset detects
// the layout and calls its reader (io/dataset_<layout>.cpp); the writer of our layout is
// io/dataset_writer.h. docs/datasets.md has the details.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "camera/camera.h"
#include "events/event_stream.h"
#include "io/events_txt.h"  // TimeUnit
#include "io/image.h"

namespace evflow::io {

struct View {
  std::string name;
  Image blurry;                                 // linear RGB; empty for novel views
  Camera camera;                                // OpenCV world_to_camera + intrinsics matching the image size
  double exposure_start = 0, exposure_end = 0;  // seconds, on the events' clock
  std::optional<Image> sharp_mid;               // ground truth at mid-exposure (novel views: the test image)
};

struct Dataset {
  std::string layout;       // "evflow", "recording", "e3nerf", "ebad", "llff", "nerf_synthetic"
  std::vector<View> train;  // blurry training views
  std::vector<View> novel;  // test views: camera + sharp image (sharp_mid)
  EventStream events;       // t in seconds; empty for EBAD-NeRF
  // EBAD-NeRF: signed per-pixel event counts, shape [train.size(), bins, H*W] (row v belongs to
  // train[v], pixel index y * W + x). Empty for the other layouts.
  std::vector<float> event_counts;
  std::vector<size_t> event_counts_shape;
  double near = 0, far = 0;  // scene depth bounds (min near, max far over all poses)
  // Optional sparse points (COLMAP's, from `evflow poses`): N x 6 floats, x y z in the poses'
  // world frame and r g b as display sRGB in [0, 1]; `init=points` starts training from them.
  std::vector<float> points;
  nlohmann::json manifest;  // our dataset.json, or a description of the foreign layout
  std::string root;         // folder it was read from
};

struct LoadOptions {
  // E3NeRF events/NNN.txt timestamp unit; nullopt = detect from the first event line
  // (a token with '.' or an exponent: seconds; an integer: microseconds).
  std::optional<TimeUnit> e3nerf_time_unit;
  // EBAD-NeRF: view i (0-based, poses_bounds order) is a test view when i % test_every == 0.
  int ebad_test_every = 8;
};

// Detects the layout of `dir` (dataset.json: ours; recording.json: a recording, identity poses
// until `evflow poses` gives it some; events.npy: EBAD-NeRF; events/ + gt/:
// E3NeRF) and reads it. Throws std::runtime_error naming the offending file and what is wrong
// (missing folder/file/view, image count vs poses rows, wrong image size, bad events, truncated
// or malformed files).
Dataset load_dataset(const std::filesystem::path& dir, const LoadOptions& options = {});

}  // namespace evflow::io
