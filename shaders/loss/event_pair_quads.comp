#version 450
// Event loss, forward part of one pair per pixel (pool 1) when H*W is a multiple of 4: what
// loss/event_pair writes (E and D per pixel in scratch planes 0 and 1, the workgroup sums of E*D,
// D*D, E*E), four pixels per invocation through vec4 accesses (CPU drivers loop over the lanes
// for every access, so one vec4 access costs what one float access costs).
// Build loss/event_pair_quads_rev (EVF_EVENT_REVERSED) also sums the pair for the time-reversed
// frame order from the same counts: D' = L(frame F-1-j) - L(frame F-1-s), the sums of E*D', D'*D',
// E*E into a second set of partials, what this kernel run on the reversed frames would write.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
// The inputs are read as texels: on lavapipe straight-line code, where a storage-buffer load is a
// loop over the lanes (a buffer is a whole number of vec4s, gpu/buffer.h).
layout(binding = kEventPairBindCounts) uniform usamplerBuffer Counts;  // R32UI
layout(binding = kEventPairBindFrameS) uniform samplerBuffer FrameS;   // planar RGB at t_s
layout(binding = kEventPairBindFrameJ) uniform samplerBuffer FrameJ;   // planar RGB at t_j
layout(std430, binding = kEventPairBindScratch) writeonly buffer Scratch { vec4 scratch[]; };  // [E][D]
layout(std430, binding = kEventPairBindPartials) writeonly buffer Partials { vec4 partials[]; };
#ifdef EVF_EVENT_REVERSED
layout(binding = kEventPairBindFrameRS) uniform samplerBuffer FrameRS;  // the reversed order's t_s
layout(binding = kEventPairBindFrameRJ) uniform samplerBuffer FrameRJ;  // the reversed order's t_j
layout(std430, binding = kEventPairBindPartialsR) writeonly buffer PartialsR { vec4 partials_r[]; };
#endif
layout(push_constant) uniform PC { EventPairPC pc; };
#ifdef EVF_EVENT_REVERSED
#define EVF_LOSS_GROUP_SUM2
#endif
#include "loss/ssim_math.glsl"
#include "loss/event_math.glsl"
#include "common/texel.glsl"

// Four pixels' plane values: uint counts, or (binned events) the bits of float amounts.
vec4 plane_amounts(uint i) {
  uvec4 v = evf_texel_uvec4(Counts, i);
  return pc.counts_float != 0u ? uintBitsToFloat(v) : vec4(v);
}

// Log-luminance of the four pixels of quad q of a planar RGB frame.
vec4 frame_log_luma(samplerBuffer frame, uint q, uint quads) {
  return event_log_luma(texelFetch(frame, int(q)), texelFetch(frame, int(quads + q)),
                        texelFetch(frame, int(2u * quads + q)), pc.eps);
}

void main() {
  uint quads = pc.width * pc.height / 4u, q = evf_linear_invocation(kLossGroupSize);
  vec4 v = vec4(0.0), v_r = vec4(0.0);
  if (q < quads) {
    vec4 e = vec4(0.0);
    for (uint k = pc.plane_first; k <= pc.plane_last; ++k) {
      uint base = k * 2u * quads;
      e += pc.theta_pos * plane_amounts(base + q) - pc.theta_neg * plane_amounts(base + quads + q);
    }
    vec4 d = frame_log_luma(FrameJ, q, quads) - frame_log_luma(FrameS, q, quads);
    scratch[q] = e;
    scratch[quads + q] = d;
    v = vec4(dot(e, d), dot(d, d), dot(e, e), 0.0);
#ifdef EVF_EVENT_REVERSED
    vec4 d_r = frame_log_luma(FrameRJ, q, quads) - frame_log_luma(FrameRS, q, quads);
    v_r = vec4(dot(e, d_r), dot(d_r, d_r), dot(e, e), 0.0);
#endif
  }
#ifdef EVF_EVENT_REVERSED
  vec4 total, total_r;
  loss_group_sum2(v, v_r, total, total_r);
  if (gl_LocalInvocationIndex == 0u) {
    partials[evf_linear_group()] = total;
    partials_r[evf_linear_group()] = total_r;
  }
#else
  vec4 total = loss_group_sum(v);
  if (gl_LocalInvocationIndex == 0u) partials[evf_linear_group()] = total;
#endif
}
