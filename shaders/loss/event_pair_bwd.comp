#version 450
// Event loss, backward part of one pair (loss_layout.h, EventPairPC): the gradient of
// l = || E/nE - D/nD ||^2 w.r.t. both frames' RGB, added into their gradient images, and the
// pair's value. A pixel's D is part of its pooling cell's sum, so it takes the cell's dl/dD.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kEventPairBwdBindFrameS) readonly buffer FrameS { float frame_s[]; };
layout(std430, binding = kEventPairBwdBindFrameJ) readonly buffer FrameJ { float frame_j[]; };
layout(std430, binding = kEventPairBwdBindScratch) readonly buffer Scratch { float scratch[]; };
layout(std430, binding = kEventPairBwdBindSums) readonly buffer Sums { float sums[]; };
layout(std430, binding = kEventPairBwdBindGradS) buffer GradS { float grad_s[]; };
layout(std430, binding = kEventPairBwdBindGradJ) buffer GradJ { float grad_j[]; };
layout(std430, binding = kEventPairBwdBindValues) buffer Values { float values[]; };
layout(push_constant) uniform PC { EventPairPC pc; };
#include "loss/event_math.glsl"

void main() {
  uint hw = pc.width * pc.height;
  uint p = evf_linear_invocation(kLossGroupSize);
  float ed = sums[4u * pc.pair], dd = sums[4u * pc.pair + 1u], ee = sums[4u * pc.pair + 2u];
  if (p == 0u) {
    float v = pc.value_scale * event_pair_loss(ed, dd, ee, pc.norm_floor2);
    values[pc.value_index] = pc.value_accumulate != 0u ? values[pc.value_index] + v : v;
  }
  if (p >= hw) return;
  uint cw = event_cells(pc.width, pc.pool), cells = cw * event_cells(pc.height, pc.pool);
  uint c = (p / pc.width / pc.pool) * cw + (p % pc.width) / pc.pool;
  float g = event_pair_dl_dd(scratch[c], scratch[cells + c], ed, dd, ee, pc.norm_floor2);
  g *= pc.grad_scale;
  vec3 cs = vec3(frame_s[p], frame_s[hw + p], frame_s[2u * hw + p]);
  vec3 cj = vec3(frame_j[p], frame_j[hw + p], frame_j[2u * hw + p]);
  vec3 gj = g * event_log_luma_grad(cj, pc.eps), gs = -g * event_log_luma_grad(cs, pc.eps);
  grad_j[p] += gj.r; grad_j[hw + p] += gj.g; grad_j[2u * hw + p] += gj.b;
  grad_s[p] += gs.r; grad_s[hw + p] += gs.g; grad_s[2u * hw + p] += gs.b;
}
