// A Camera as the push-constant block the shaders project with (shaders/common/camera_layout.h).
#pragma once
#include <algorithm>

#include "common/camera_layout.h"
#include "splat/gaussians.h"

namespace evflow {

inline shaderio::CameraPC camera_pc(const Camera& cam) {
  shaderio::CameraPC pc{};
  pc.row0 = {float(cam.R[0]), float(cam.R[1]), float(cam.R[2]), float(cam.t[0])};
  pc.row1 = {float(cam.R[3]), float(cam.R[4]), float(cam.R[5]), float(cam.t[1])};
  pc.row2 = {float(cam.R[6]), float(cam.R[7]), float(cam.R[8]), float(cam.t[2])};
  pc.intrin = {float(cam.fx), float(cam.fy), float(cam.cx), float(cam.cy)};
  pc.width = cam.width;
  pc.height = cam.height;
  pc.near_plane = float(cam.near_plane);
  pc.far_plane = float(std::min(cam.far_plane, 3.0e38));
  return pc;
}

}  // namespace evflow
