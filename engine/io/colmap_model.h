// Reader of a COLMAP sparse model in its text form (cameras.txt, images.txt, points3D.txt, as
// `colmap model_converter --output_type TXT` writes them); docs/datasets.md.
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "camera/camera.h"

namespace evflow::io {

struct ColmapImage {
  uint32_t id = 0, camera_id = 0;
  std::string name;  // the image's path relative to COLMAP's image folder
  Camera camera;     // world_to_camera from the quaternion and translation, intrinsics from its camera
};

struct ColmapPoint {
  std::array<double, 3> xyz{};
  std::array<uint8_t, 3> rgb{};
  double error = 0;                 // mean reprojection error, pixels
  std::vector<uint32_t> image_ids;  // the images of its track (an image may appear twice)
};

struct ColmapModel {
  std::vector<ColmapImage> images;  // in the file's order
  std::vector<ColmapPoint> points;
};

// Reads `dir`/cameras.txt, images.txt and points3D.txt. Camera models PINHOLE and SIMPLE_PINHOLE
// (the only ones without distortion) are accepted. COLMAP's axes and pixel convention (pixel
// centres at +0.5) are ours, so poses and intrinsics are taken as they are. Throws
// std::runtime_error naming the file and line on anything malformed, an unknown camera id or
// another camera model.
ColmapModel read_colmap_text(const std::filesystem::path& dir);

}  // namespace evflow::io
