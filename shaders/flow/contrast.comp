#version 450
// Contrast of each blurred IWE B: G = sum over pixels of gx^2 + gy^2 with central differences
// gx(x) = (B(x+1) - B(x-1)) / 2 (B = 0 outside the image). Writes one partial sum of G per
// workgroup (workgroups never straddle two images; common/group_sum.glsl: reproducible) and the
// adjoint scale[image] * dG/dB, where dG/dB(x) = gx(x-1) - gx(x+1) + gy(x-1) - gy(x+1) over the
// differences that exist.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
#define EVF_GROUP_SUM_SIZE kFlowGroupSize
#include "common/group_sum.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowContrastBindBlurred) readonly buffer Blurred { float blurred[]; };
layout(std430, binding = kFlowContrastBindScale) readonly buffer Scale { float scale[]; };
layout(std430, binding = kFlowContrastBindAdjoint) writeonly buffer Adjoint { float adjoint[]; };
layout(std430, binding = kFlowContrastBindPartials) writeonly buffer Partials { float partials[]; };
layout(push_constant) uniform PC { FlowContrastPC pc; };

uint g_base;
float b_at(ivec2 q) {
  if (q.x < 0 || q.y < 0 || q.x >= int(pc.width) || q.y >= int(pc.height)) return 0.0;
  return blurred[g_base + uint(q.y) * pc.width + uint(q.x)];
}
bool inside(ivec2 q) { return q.x >= 0 && q.y >= 0 && q.x < int(pc.width) && q.y < int(pc.height); }
// The central difference along `s` at q (0 where q is outside: no such term).
float diff(ivec2 q, ivec2 s) { return inside(q) ? 0.5 * (b_at(q + s) - b_at(q - s)) : 0.0; }

void main() {
  const uint hw = pc.width * pc.height;
  uint group = evf_linear_group();
  uint image = group / pc.groups, pixel = (group % pc.groups) * kFlowGroupSize + gl_LocalInvocationIndex;
  g_base = image * hw;
  float g = 0.0;
  if (image < pc.images && pixel < hw) {
    ivec2 q = ivec2(pixel % pc.width, pixel / pc.width);
    const ivec2 sx = ivec2(1, 0), sy = ivec2(0, 1);
    float gx = diff(q, sx), gy = diff(q, sy);
    g = gx * gx + gy * gy;
    float d = diff(q - sx, sx) - diff(q + sx, sx) + diff(q - sy, sy) - diff(q + sy, sy);
    adjoint[g_base + pixel] = scale[image] * d;
  }
  const float total = evf_group_sum(vec2(g, 0.0)).x;
  if (gl_LocalInvocationIndex == 0u && image < pc.images) partials[group] = total;
}
