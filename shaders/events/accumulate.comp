#version 450
// Per-pixel event counts of one index range of the packed events (events_layout.h), positive and
// negative separately, with integer atomics (exact and order-independent).
#extension GL_GOOGLE_include_directive : require
#include "events/events_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kEventGroupSize) in;
layout(std430, binding = kEventAccumulateBindPacked) readonly buffer Packed { uint packed_events[]; };
layout(std430, binding = kEventAccumulateBindCounts) buffer Counts { uint counts[]; };
layout(push_constant) uniform PC { EventAccumulatePC pc; };

void main() {
  uint i = evf_linear_invocation(kEventGroupSize);
  if (i >= pc.count) return;
  uint e = packed_events[pc.first + i];
  uint x = e & kEventCoordMask, y = (e >> kEventCoordBits) & kEventCoordMask;
  if (x >= pc.width || y >= pc.height) return;  // the host validates; never write out of range
  uint hw = pc.width * pc.height;
  uint base = pc.plane * 2u * hw + ((e & kEventPositiveBit) != 0u ? 0u : hw);
  atomicAdd(counts[base + y * pc.width + x], 1u);
}
