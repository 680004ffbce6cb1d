#version 450
// Exclusive scan within blocks of kScanBlock elements. One invocation scans EVF_SCAN_ITEMS
// consecutive elements; the workgroup combines the partial sums in shared memory; the block total
// goes to sums[]. Two builds of one block size (scan_layout.h): 256 invocations of 16 elements
// (GPUs), and "_wide", 16 invocations of 256 read and written four at a time (CPU drivers).
// EVF_SCAN_SINGLE (the "_wide_single" build, CPU drivers, up to kScanSingleMax elements): one
// workgroup scans everything, each invocation a sixteenth (a multiple of 4), so that no second
// level and no add pass follow (on lavapipe each dispatch has a fixed cost of about 0.1 ms).
#extension GL_GOOGLE_include_directive : require
#include "scan/scan_layout.h"
#include "scan/scan_build.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = EVF_SCAN_GROUP) in;
#ifdef EVF_SCAN_WIDE
// Four elements to an access (a buffer is a whole number of 16 bytes, gpu/buffer.h): on CPU
// drivers every storage access is a loop over the SIMD lanes.
layout(std430, binding = kScanBlockBindIn) readonly buffer In { uvec4 values_in4[]; };
layout(std430, binding = kScanBlockBindOut) writeonly buffer Out { uvec4 values_out4[]; };
#else
layout(std430, binding = kScanBlockBindIn) readonly buffer In { uint values_in[]; };
layout(std430, binding = kScanBlockBindOut) writeonly buffer Out { uint values_out[]; };
#endif
layout(std430, binding = kScanBlockBindSums) writeonly buffer Sums { uint block_sums[]; };
layout(push_constant) uniform PC { ScanPC pc; };
shared uint partial[2][EVF_SCAN_GROUP];

// in[i .. i + 4), zero at and past n_in (i a multiple of 4).
uvec4 load4(uint i) {
#ifdef EVF_SCAN_WIDE
  uvec4 v = i < pc.n_in ? values_in4[i >> 2u] : uvec4(0u);
  return mix(uvec4(0u), v, lessThan(uvec4(i) + uvec4(0u, 1u, 2u, 3u), uvec4(pc.n_in)));
#else
  uvec4 v = uvec4(0u);
  for (uint c = 0u; c < 4u; ++c)
    if (i + c < pc.n_in) v[c] = values_in[i + c];
  return v;
#endif
}

// out[i .. i + 4) = v, only below n_out.
void store4(uint i, uvec4 v) {
#ifdef EVF_SCAN_WIDE
  if (i + 4u <= pc.n_out) {
    values_out4[i >> 2u] = v;
    return;
  }
  for (uint c = 0u; c < 4u; ++c)
    if (i + c < pc.n_out) values_out4[i >> 2u][c] = v[c];
#else
  for (uint c = 0u; c < 4u; ++c)
    if (i + c < pc.n_out) values_out[i + c] = v[c];
#endif
}

void main() {
  uint lid = gl_LocalInvocationIndex;
#ifdef EVF_SCAN_SINGLE
  uint block = 0u, items = (max(pc.n_in, pc.n_out) + 4u * EVF_SCAN_GROUP - 1u) / (4u * EVF_SCAN_GROUP) * 4u;
  uint base = lid * items;
#else
  uint block = evf_linear_group(), items = EVF_SCAN_ITEMS;
  uint base = block * kScanBlock + lid * EVF_SCAN_ITEMS;
#endif
  uint sum = 0;
  for (uint k = 0; k < items && base + k < pc.n_in; k += 4u) {
    uvec4 v = load4(base + k);
    sum += (v.x + v.y) + (v.z + v.w);
  }
  partial[0][lid] = sum;
  barrier();
  uint src = 0;
  for (uint off = 1; off < EVF_SCAN_GROUP; off <<= 1) {
    uint x = partial[src][lid];
    if (lid >= off) x += partial[src][lid - off];
    partial[1 - src][lid] = x;
    src = 1 - src;
    barrier();
  }
  uint run = partial[src][lid] - sum;  // exclusive prefix of this invocation
  for (uint k = 0; k < items && base + k < pc.n_out; k += 4u) {
    uvec4 v = load4(base + k);  // the inputs read again (in and out may alias)
    uvec4 out4 = uvec4(run, run + v.x, run + v.x + v.y, run + v.x + v.y + v.z);
    store4(base + k, out4);
    run = out4.w + v.w;
  }
  if (lid == EVF_SCAN_GROUP - 1u) block_sums[block] = partial[src][EVF_SCAN_GROUP - 1u];
}
