#version 450
// Warped-event loss, forward part of one interval (loss_layout.h, WarpedEventPC): the measured
// warped events M and the predicted change P per pixel, and the workgroup sums of M*P, P*P, M*M.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kWarpedEventBindPlanes) readonly buffer Planes { float planes[]; };
layout(std430, binding = kWarpedEventBindFrame) readonly buffer Frame { float frame[]; };         // planar RGB at t_j
layout(std430, binding = kWarpedEventBindScratch) writeonly buffer Scratch { float scratch[]; };  // [M][P], H*W each
layout(std430, binding = kWarpedEventBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { WarpedEventPC pc; };
#include "loss/ssim_math.glsl"
#include "loss/event_math.glsl"
#include "loss/warped_math.glsl"

void main() {
  uint hw = pc.width * pc.height;
  uint p = evf_linear_invocation(kLossGroupSize);
  vec4 v = vec4(0.0);
  if (p < hw) {
    float m = 0.0, d = 0.0;
    if (warped_interior(p % pc.width, p / pc.width)) {
      m = planes[warped_plane(0u, hw) + p];
      d = warped_predicted(p, hw);
    }
    scratch[p] = m;
    scratch[hw + p] = d;
    v = vec4(m * d, d * d, m * m, 0.0);
  }
  vec4 total = loss_group_sum(v);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
