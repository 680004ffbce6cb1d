#version 450
// Adds each block's scanned offset to its 1024 elements. One invocation: 4 elements.
#extension GL_GOOGLE_include_directive : require
#include "scan/scan_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kScanGroupSize) in;
layout(std430, binding = kScanAddBindValues) buffer Values { uint values[]; };
layout(std430, binding = kScanAddBindOffsets) readonly buffer Offsets { uint block_offsets[]; };
layout(push_constant) uniform PC { ScanPC pc; };
void main() {
  uint block = evf_linear_group();
  uint add = block_offsets[block];
  uint base = block * kScanBlock + gl_LocalInvocationIndex * kScanItems;
  for (uint k = 0; k < kScanItems; ++k)
    if (base + k < pc.n_out) values[base + k] += add;
}
