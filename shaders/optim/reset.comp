#version 450
// Zeroes the Adam moments of selected rows (mode 0: mask per row; mode 1: list of rows).
#extension GL_GOOGLE_include_directive : require
#include "optim/optim_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kOptimGroupSize) in;
layout(std430, binding = kOptimResetBindM) writeonly buffer M { float exp_avg[]; };
layout(std430, binding = kOptimResetBindV) writeonly buffer V { float exp_avg_sq[]; };
layout(std430, binding = kOptimResetBindSelect) readonly buffer Select { uint select_rows[]; };
layout(push_constant) uniform PC { RowsPC pc; };

void main() {
  uint i = evf_linear_invocation(kOptimGroupSize);
  if (i >= pc.rows * pc.width) return;
  uint r = i / pc.width;
  uint k = i - r * pc.width;
  uint row;
  if (pc.mode == 0u) {
    if (select_rows[r] == 0u) return;
    row = r;
  } else {
    row = select_rows[r];
    if (row >= pc.total_rows) return;
  }
  uint j = row * pc.width + k;
  exp_avg[j] = 0.0;
  exp_avg_sq[j] = 0.0;
}
