#version 450
// The LDI's event tensor of one side of a frame time (ldi_layout.h, LdiBinPC): each event of the
// side adds 1 to its (time bin, polarity) channel at its pixel of the crop.
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "events/events_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiBinBindPacked) readonly buffer Packed { uint packed_events[]; };
layout(std430, binding = kLdiBinBindCounts) buffer Counts { uint counts[]; };
layout(push_constant) uniform PC { LdiBinPC pc; };

uint bound_at(uint k) { return pc.bound[k / 4u][k % 4u]; }

void main() {
  uint first = bound_at(0u), index = first + evf_linear_invocation(kLdiGroupSize);
  if (index >= bound_at(pc.bins)) return;
  uint k = 0u;  // index-order interval of the event
  while (k + 1u < pc.bins && index >= bound_at(k + 1u)) ++k;
  uint e = packed_events[index];
  uint x = e & kEventCoordMask, y = (e >> kEventCoordBits) & kEventCoordMask;
  if (x < pc.crop_x || y < pc.crop_y || x - pc.crop_x >= pc.crop_w || y - pc.crop_y >= pc.crop_h) return;
  bool positive = (e & kEventPositiveBit) != 0u;
  uint bin = k;
  if (pc.reversed != 0u) {
    bin = pc.bins - 1u - k;
    positive = !positive;
  }
  uint channel = pc.channel_base + 2u * bin + (positive ? 0u : 1u);
  atomicAdd(counts[(channel * pc.crop_h + (y - pc.crop_y)) * pc.crop_w + (x - pc.crop_x)], 1u);
}
