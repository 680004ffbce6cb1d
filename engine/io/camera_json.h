// Cameras as JSON, to render from chosen poses (`evflow render --camera`, docs/cli.md):
//
//   {"width": 640, "height": 480, "fx": 500, "fy": 500, "cx": 320, "cy": 240,
//    "w2c": [[r00, r01, r02, t0], [r10, r11, r12, t1], [r20, r21, r22, t2], [0, 0, 0, 1]]}
//
// "w2c" maps world to camera in OpenCV axes (x right, y down, z forward): 4 rows, 3 rows, or 16
// numbers row-major. A file holds one camera, a list of them, or {"cameras": [...]}.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "camera/camera.h"

namespace evflow::io {

// Throws std::runtime_error naming the file, the camera's index and what is wrong.
std::vector<Camera> read_cameras_json(const std::filesystem::path& path);
// `where` names the camera in errors.
Camera camera_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json camera_to_json(const Camera& c);

}  // namespace evflow::io
