// The camera as push constants, shared by every module that projects (splat, densify):
// world_to_camera rows with the translation in w, and intrinsics. engine/splat/camera_pc.h fills it.
#ifndef EVF_CAMERA_LAYOUT_H
#define EVF_CAMERA_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
struct CameraPC {
  vec4 row0;
  vec4 row1;
  vec4 row2;
  vec4 intrin;      // fx, fy, cx, cy
  uint width;
  uint height;
  float near_plane;
  float far_plane;
};
EVF_NAMESPACE_END
#endif
