#version 450
// One bin of pre-binned signed event counts, weighted, added to a float plane of positive and
// negative amounts (events_layout.h, BinnedAccumulatePC). One invocation per pixel: no atomics.
#extension GL_GOOGLE_include_directive : require
#include "events/events_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kEventGroupSize) in;
layout(std430, binding = kBinnedAccumulateBindBinned) readonly buffer Binned { float binned[]; };
layout(std430, binding = kBinnedAccumulateBindCounts) buffer Counts { float counts[]; };
layout(push_constant) uniform PC { BinnedAccumulatePC pc; };

void main() {
  uint p = evf_linear_invocation(kEventGroupSize);
  uint hw = pc.width * pc.height;
  if (p >= hw) return;
  float c = binned[pc.offset + p];
  uint base = pc.plane * 2u * hw;
  counts[base + p] += pc.weight * max(c, 0.0);
  counts[base + hw + p] += pc.weight * max(-c, 0.0);
}
