#version 450
// Event loss, backward part of one pair per pixel (pool 1) when H*W is a multiple of 4: what
// loss/event_pair_bwd adds into both frames' gradient images (and the pair's value), four pixels
// per invocation through vec4 accesses, after loss/event_pair_quads.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
// The frames and the scratch are read as texels (straight-line code on lavapipe).
layout(binding = kEventPairBwdBindFrameS) uniform samplerBuffer FrameS;
layout(binding = kEventPairBwdBindFrameJ) uniform samplerBuffer FrameJ;
layout(binding = kEventPairBwdBindScratch) uniform samplerBuffer Scratch;
layout(std430, binding = kEventPairBwdBindSums) readonly buffer Sums { float sums[]; };
// What it adds to is read through texel views of the same buffers (each element read, then
// written, by its own invocation alone): a `+=` on a storage buffer is two loops over the lanes.
layout(std430, binding = kEventPairBwdBindGradS) writeonly buffer GradS { vec4 grad_s[]; };
layout(std430, binding = kEventPairBwdBindGradJ) writeonly buffer GradJ { vec4 grad_j[]; };
layout(binding = kEventPairBwdBindGradSIn) uniform samplerBuffer GradSIn;
layout(binding = kEventPairBwdBindGradJIn) uniform samplerBuffer GradJIn;
layout(std430, binding = kEventPairBwdBindValues) buffer Values { float values[]; };
layout(push_constant) uniform PC { EventPairPC pc; };
#include "loss/event_math.glsl"

void main() {
  uint quads = pc.width * pc.height / 4u, q = evf_linear_invocation(kLossGroupSize);
  float ed = sums[4u * pc.pair], dd = sums[4u * pc.pair + 1u], ee = sums[4u * pc.pair + 2u];
  if (q == 0u) {
    float v = pc.value_scale * event_pair_loss(ed, dd, ee, pc.norm_floor2);
    values[pc.value_index] = pc.value_accumulate != 0u ? values[pc.value_index] + v : v;
  }
  if (q >= quads) return;
  vec4 g = pc.grad_scale * event_pair_dl_dd(texelFetch(Scratch, int(q)), texelFetch(Scratch, int(quads + q)), ed, dd,
                                            ee, pc.norm_floor2);
  uint r = q, gr = quads + q, b = 2u * quads + q;
  vec4 yj = event_luma(texelFetch(FrameJ, int(r)), texelFetch(FrameJ, int(gr)), texelFetch(FrameJ, int(b)));
  vec4 ys = event_luma(texelFetch(FrameS, int(r)), texelFetch(FrameS, int(gr)), texelFetch(FrameS, int(b)));
  grad_j[r] = texelFetch(GradJIn, int(r)) + g * event_log_luma_grad(yj, kEventLuma.r, pc.eps);
  grad_j[gr] = texelFetch(GradJIn, int(gr)) + g * event_log_luma_grad(yj, kEventLuma.g, pc.eps);
  grad_j[b] = texelFetch(GradJIn, int(b)) + g * event_log_luma_grad(yj, kEventLuma.b, pc.eps);
  grad_s[r] = texelFetch(GradSIn, int(r)) - g * event_log_luma_grad(ys, kEventLuma.r, pc.eps);
  grad_s[gr] = texelFetch(GradSIn, int(gr)) - g * event_log_luma_grad(ys, kEventLuma.g, pc.eps);
  grad_s[b] = texelFetch(GradSIn, int(b)) - g * event_log_luma_grad(ys, kEventLuma.b, pc.eps);
}
