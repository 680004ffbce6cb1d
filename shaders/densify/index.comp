#version 450
// Per old Gaussian g: its rows offsets[g] .. offsets[g+1] of the new cloud: the parameter
// source row, the optimizer-state source row (kDensifyNoSource: zero state) and the row code.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kDensifyIndexBindDecision) readonly buffer Decision { uint decision[]; };
layout(std430, binding = kDensifyIndexBindOffsets) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = kDensifyIndexBindParamSrc) writeonly buffer ParamSrc { uint param_src[]; };
layout(std430, binding = kDensifyIndexBindStateSrc) writeonly buffer StateSrc { uint state_src[]; };
layout(std430, binding = kDensifyIndexBindCode) writeonly buffer Code { uint row_code[]; };
layout(push_constant) uniform PC { EmitPC pc; };

void put(uint r, uint src, uint state, uint code) {
  param_src[r] = src;
  state_src[r] = state;
  row_code[r] = code;
}

void main() {
  uint g = evf_linear_invocation(kDensifyGroupSize);
  if (g >= pc.count) return;
  uint dec = decision[g];
  uint r = offsets[g];
  bool grown = (dec & kDecGrown) != 0u;
  if (grown && (dec & kDecSplit) != 0u) {
    put(r, g, kDensifyNoSource, kRowChild0);
    put(r + 1u, g, kDensifyNoSource, kRowChild0 + 1u);
    return;
  }
  if ((dec & kDecKeep) != 0u) put(r++, g, g, kRowCopy);
  if (grown && (dec & kDecClone) != 0u) put(r, g, kDensifyNoSource, kRowCopy);
}
