#version 450
// Event loss, forward part of one pair per pixel (pool 1) when H*W is a multiple of 4: what
// loss/event_pair writes (E and D per pixel in scratch planes 0 and 1, the workgroup sums of E*D,
// D*D, E*E), four pixels per invocation through vec4 accesses (CPU drivers loop over the lanes
// for every access, so one vec4 access costs what one float access costs).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kEventPairBindCounts) readonly buffer Counts { uvec4 event_counts[]; };
layout(std430, binding = kEventPairBindFrameS) readonly buffer FrameS { vec4 frame_s[]; };     // planar RGB at t_s
layout(std430, binding = kEventPairBindFrameJ) readonly buffer FrameJ { vec4 frame_j[]; };     // planar RGB at t_j
layout(std430, binding = kEventPairBindScratch) writeonly buffer Scratch { vec4 scratch[]; };  // [E][D]
layout(std430, binding = kEventPairBindPartials) writeonly buffer Partials { vec4 partials[]; };
layout(push_constant) uniform PC { EventPairPC pc; };
#include "loss/ssim_math.glsl"
#include "loss/event_math.glsl"

// Four pixels' plane values: uint counts, or (binned events) the bits of float amounts.
vec4 plane_amounts(uint i) {
  uvec4 v = event_counts[i];
  return pc.counts_float != 0u ? uintBitsToFloat(v) : vec4(v);
}

void main() {
  uint quads = pc.width * pc.height / 4u, q = evf_linear_invocation(kLossGroupSize);
  vec4 v = vec4(0.0);
  if (q < quads) {
    vec4 e = vec4(0.0);
    for (uint k = pc.plane_first; k <= pc.plane_last; ++k) {
      uint base = k * 2u * quads;
      e += pc.theta_pos * plane_amounts(base + q) - pc.theta_neg * plane_amounts(base + quads + q);
    }
    vec4 d = event_log_luma(frame_j[q], frame_j[quads + q], frame_j[2u * quads + q], pc.eps) -
             event_log_luma(frame_s[q], frame_s[quads + q], frame_s[2u * quads + q], pc.eps);
    scratch[q] = e;
    scratch[quads + q] = d;
    v = vec4(dot(e, d), dot(d, d), dot(e, e), 0.0);
  }
  vec4 total = loss_group_sum(v);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
}
