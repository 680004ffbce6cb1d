#version 450
// Event loss, forward part of one pair (loss_layout.h, EventPairPC): E and D per pooling cell (the
// sums over its pool x pool pixels; one pixel at pool 1) and the workgroup sums of E*D, D*D, E*E.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kEventPairBindCounts) readonly buffer Counts { uint event_counts[]; };
layout(std430, binding = kEventPairBindFrameS) readonly buffer FrameS { float frame_s[]; };     // planar RGB at t_s
layout(std430, binding = kEventPairBindFrameJ) readonly buffer FrameJ { float frame_j[]; };     // planar RGB at t_j
layout(std430, binding = kEventPairBindScratch) writeonly buffer Scratch { float scratch[]; };  // [E][D], a value per cell each
layout(std430, binding = kEventPairBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { EventPairPC pc; };
#include "loss/ssim_math.glsl"
#include "loss/event_math.glsl"

// A plane value: a uint count, or (binned events) the bits of a float amount.
float plane_amount(uint i) {
  return pc.counts_float != 0u ? uintBitsToFloat(event_counts[i]) : float(event_counts[i]);
}

// The event side: the interval planes' signed, threshold-weighted counts at pixel p.
float event_level(uint p, uint hw) {
  float e = 0.0;
  for (uint k = pc.plane_first; k <= pc.plane_last; ++k) {
    uint base = k * 2u * hw;
    e += pc.theta_pos * plane_amount(base + p) - pc.theta_neg * plane_amount(base + hw + p);
  }
  return e;
}

void main() {
  uint hw = pc.width * pc.height, cw = event_cells(pc.width, pc.pool), cells = cw * event_cells(pc.height, pc.pool);
  uint c = evf_linear_invocation(kLossGroupSize);
  vec4 v = vec4(0.0);
  if (c < cells) {
    uvec2 x0 = uvec2(c % cw, c / cw) * pc.pool, x1 = min(x0 + pc.pool, uvec2(pc.width, pc.height));
    float e = 0.0, d = 0.0;
    for (uint y = x0.y; y < x1.y; ++y)
      for (uint x = x0.x; x < x1.x; ++x) {
        uint p = y * pc.width + x;
        vec3 cs = vec3(frame_s[p], frame_s[hw + p], frame_s[2u * hw + p]);
        vec3 cj = vec3(frame_j[p], frame_j[hw + p], frame_j[2u * hw + p]);
        e += event_level(p, hw);
        d += event_log_luma(cj, pc.eps) - event_log_luma(cs, pc.eps);
      }
    scratch[c] = e;
    scratch[cells + c] = d;
    v = vec4(e * d, d * d, e * e, 0.0);
  }
  vec4 total = loss_group_sum(v);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
