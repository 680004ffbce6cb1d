#version 450
// Event loss, the value of one pair alone (loss_layout.h, EventPairPC): what loss/event_pair_bwd
// writes into values[value_index], without the gradients. One invocation.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
layout(local_size_x = 1) in;
layout(std430, binding = kEventPairValueBindSums) readonly buffer Sums { float sums[]; };
layout(std430, binding = kEventPairValueBindValues) buffer Values { float values[]; };
layout(push_constant) uniform PC { EventPairPC pc; };
#include "loss/event_math.glsl"

void main() {
  float ed = sums[4u * pc.pair], dd = sums[4u * pc.pair + 1u], ee = sums[4u * pc.pair + 2u];
  float v = pc.value_scale * event_pair_loss(ed, dd, ee, pc.norm_floor2);
  values[pc.value_index] = pc.value_accumulate != 0u ? values[pc.value_index] + v : v;
}
