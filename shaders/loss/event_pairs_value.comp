#version 450
// Event loss, the value of every pair of an exposure from their sums (loss_layout.h,
// EventPairsPC): sum over pairs, in order, of value_scale * l into values[value_index] and, with
// `reversed`, the time-reversed order's into reversed_values[reversed_index]. One invocation.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
layout(local_size_x = 1) in;
layout(std430, binding = kEventPairsValueBindSums) readonly buffer Sums { float sums[]; };
layout(std430, binding = kEventPairsValueBindValues) buffer Values { float values[]; };
layout(std430, binding = kEventPairsValueBindReversed) buffer Reversed { float reversed_values[]; };
layout(push_constant) uniform PC { EventPairsPC pc; };
#include "loss/event_math.glsl"

void main() {
  float v = 0.0, v_r = 0.0;
  for (uint q = 0u; q < pc.pairs; ++q) {
    uint i = kEventPairsSumsPerPair * q;
    float l = pc.value_scale * event_pair_loss(sums[i], sums[i + 1u], sums[i + 2u], pc.norm_floor2);
    float l_r = pc.value_scale * event_pair_loss(sums[i + 3u], sums[i + 4u], sums[i + 2u], pc.norm_floor2);
    v = q == 0u ? l : v + l;
    v_r = q == 0u ? l_r : v_r + l_r;
  }
  values[pc.value_index] = v;
  if (pc.reversed != 0u) reversed_values[pc.reversed_index] = v_r;
}
