#version 450
// Exclusive scan within blocks of kScanBlock elements. One invocation scans kScanItems consecutive elements;
// the workgroup combines the 256 partial sums in shared memory; the block total goes to sums[].
#extension GL_GOOGLE_include_directive : require
#include "scan/scan_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kScanGroupSize) in;
layout(std430, binding = kScanBlockBindIn) readonly buffer In { uint values_in[]; };
layout(std430, binding = kScanBlockBindOut) writeonly buffer Out { uint values_out[]; };
layout(std430, binding = kScanBlockBindSums) writeonly buffer Sums { uint block_sums[]; };
layout(push_constant) uniform PC { ScanPC pc; };
shared uint partial[2][kScanGroupSize];

void main() {
  uint block = evf_linear_group();
  uint lid = gl_LocalInvocationIndex;
  uint base = block * kScanBlock + lid * kScanItems;
  uint sum = 0;
  for (uint k = 0; k < kScanItems; ++k) {
    uint i = base + k;
    sum += (i < pc.n_in) ? values_in[i] : 0u;
  }
  partial[0][lid] = sum;
  barrier();
  uint src = 0;
  for (uint off = 1; off < kScanGroupSize; off <<= 1) {
    uint x = partial[src][lid];
    if (lid >= off) x += partial[src][lid - off];
    partial[1 - src][lid] = x;
    src = 1 - src;
    barrier();
  }
  uint run = partial[src][lid] - sum;  // exclusive prefix of this invocation
  for (uint k = 0; k < kScanItems; ++k) {  // the inputs read again (in and out may alias)
    uint i = base + k;
    uint v = (i < pc.n_in) ? values_in[i] : 0u;
    if (i < pc.n_out) values_out[i] = run;
    run += v;
  }
  if (lid == 255) block_sums[block] = partial[src][255];
}
