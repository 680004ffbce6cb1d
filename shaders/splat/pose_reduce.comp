#version 450
// Sums the per-workgroup pose partials into one se(3) gradient, a render's slot of the batch's
// (ReducePC::slot): a single workgroup, each invocation summing a strided share, then a tree in
// shared memory (deterministic order).
#extension GL_GOOGLE_include_directive : require
#include "splat/splat_layout.h"
layout(local_size_x = kPoseReduceGroupSize) in;
layout(std430, binding = kPoseReduceBindPartials) readonly buffer Partials { float pose_partial[]; };  // [count][6]
layout(std430, binding = kPoseReduceBindPose) writeonly buffer Pose { float v_pose[]; };               // [renders][6]
layout(push_constant) uniform PC { ReducePC pc; };
shared float red[6][kPoseReduceGroupSize];
void main() {
  uint lid = gl_LocalInvocationIndex;
  float s[6] = float[6](0, 0, 0, 0, 0, 0);
  for (uint i = lid; i < pc.count; i += kPoseReduceGroupSize)
    for (uint k = 0; k < 6; ++k) s[k] += pose_partial[i * 6 + k];
  for (uint k = 0; k < 6; ++k) red[k][lid] = s[k];
  barrier();
  for (uint st = kPoseReduceGroupSize / 2u; st > 0u; st >>= 1) {
    if (lid < st)
      for (uint k = 0; k < 6; ++k) red[k][lid] += red[k][lid + st];
    barrier();
  }
  if (lid < 6) v_pose[pc.slot * 6u + lid] = red[lid][0];
}
