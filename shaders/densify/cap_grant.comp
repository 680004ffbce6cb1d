#version 450
// Cap, step 2: grant growth to the head of the descending-gradient order while the total stays
// within max_total. base_offsets[count] is the row total without any growth.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kCapGrantBindIds) readonly buffer Ids { uint sorted_ids[]; };
layout(std430, binding = kCapGrantBindExtra) readonly buffer Extra { uint sorted_extra[]; };
layout(std430, binding = kCapGrantBindExtraScan) readonly buffer ExtraScan { uint extra_offsets[]; };
layout(std430, binding = kCapGrantBindBaseScan) readonly buffer BaseScan { uint base_offsets[]; };
layout(std430, binding = kCapGrantBindDecision) buffer Decision { uint decision[]; };
layout(std430, binding = kCapGrantBindOutCount) writeonly buffer OutCount { uint out_count[]; };
layout(push_constant) uniform PC { CapPC pc; };

void main() {
  uint j = evf_linear_invocation(kDensifyGroupSize);
  if (j >= pc.count) return;
  uint extra = sorted_extra[j];
  if (extra == 0u) return;
  uint base_total = base_offsets[pc.count];
  uint budget = pc.max_total > base_total ? pc.max_total - base_total : 0u;
  if (extra_offsets[j] + extra > budget) return;
  uint g = sorted_ids[j];
  uint dec = decision[g] | kDecGrown;
  decision[g] = dec;
  out_count[g] = out_rows(dec);
}
