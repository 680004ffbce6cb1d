#version 450
// Warped-event loss, forward part of one interval (loss_layout.h, WarpedEventPC): the measured
// warped events M and the predicted change P per pooling cell (sums over the cell's pool x pool
// pixels; one pixel at pool 1), and the workgroup sums of M*P, P*P, M*M.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kWarpedEventBindPlanes) readonly buffer Planes { float planes[]; };
layout(std430, binding = kWarpedEventBindFrame) readonly buffer Frame { float frame[]; };         // planar RGB at t_j
layout(std430, binding = kWarpedEventBindScratch) writeonly buffer Scratch { float scratch[]; };  // [M][P], a value per cell each
layout(std430, binding = kWarpedEventBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { WarpedEventPC pc; };
#include "loss/ssim_math.glsl"
#include "loss/event_math.glsl"
#include "loss/warped_math.glsl"

void main() {
  uint hw = pc.width * pc.height, cw = event_cells(pc.width, pc.pool), cells = cw * event_cells(pc.height, pc.pool);
  uint c = evf_linear_invocation(kLossGroupSize);
  vec4 v = vec4(0.0);
  if (c < cells) {
    uvec2 x0 = uvec2(c % cw, c / cw) * pc.pool, x1 = min(x0 + pc.pool, uvec2(pc.width, pc.height));
    float m = 0.0, d = 0.0;
    for (uint y = x0.y; y < x1.y; ++y)
      for (uint x = x0.x; x < x1.x; ++x)
        if (warped_interior(x, y)) {
          uint p = y * pc.width + x;
          m += planes[warped_plane(0u, hw) + p];
          d += warped_predicted(p, hw);
        }
    scratch[c] = m;
    scratch[cells + c] = d;
    v = vec4(m * d, d * d, m * m, 0.0);
  }
  vec4 total = loss_group_sum(v);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
