#version 450
// Adds each block's scanned offset to its kScanBlock elements, EVF_SCAN_ITEMS per invocation (the
// "_wide" build four to an access: scan_block.comp).
#extension GL_GOOGLE_include_directive : require
#include "scan/scan_layout.h"
#include "scan/scan_build.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = EVF_SCAN_GROUP) in;
#ifdef EVF_SCAN_WIDE
layout(std430, binding = kScanAddBindValues) buffer Values { uvec4 values[]; };
#else
layout(std430, binding = kScanAddBindValues) buffer Values { uint values[]; };
#endif
layout(std430, binding = kScanAddBindOffsets) readonly buffer Offsets { uint block_offsets[]; };
layout(push_constant) uniform PC { ScanPC pc; };
void main() {
  uint block = evf_linear_group();
  uint add = block_offsets[block];
  uint base = block * kScanBlock + gl_LocalInvocationIndex * EVF_SCAN_ITEMS;
#ifdef EVF_SCAN_WIDE
  for (uint k = 0; k < EVF_SCAN_ITEMS && base + k < pc.n_out; k += 4u) {
    uint i = base + k;
    if (i + 4u <= pc.n_out) {
      values[i >> 2u] += uvec4(add);
    } else {
      for (uint c = 0u; i + c < pc.n_out; ++c) values[i >> 2u][c] += add;
    }
  }
#else
  for (uint k = 0; k < EVF_SCAN_ITEMS; ++k)
    if (base + k < pc.n_out) values[base + k] += add;
#endif
}
