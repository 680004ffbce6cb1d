#version 450
// The chain from per-pixel flow gradients to the node grid: one workgroup per (node, interval)
// sums, over the pixels of the node's support, the node's bilinear weight times the pixel's
// gradient (common/group_sum.glsl: reproducible).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
#define EVF_GROUP_SUM_SIZE kFlowGroupSize
#include "common/group_sum.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowReduceBindGradField) readonly buffer GradField { vec2 grad_field[]; };
layout(std430, binding = kFlowReduceBindNodeGrad) writeonly buffer NodeGrad { vec2 node_grad[]; };
layout(push_constant) uniform PC { FlowNodeReducePC pc; };
vec2 flow_node(uint i) { return vec2(0.0); }
#include "flow/flow_math.glsl"

// Weight of node index `a` at pixel coordinate `pix` along an axis of `size` pixels.
float axis_weight(uint pix, uint size, uint a) {
  uint a0;
  float f;
  flow_cell(float(pix) + 0.5, size, pc.tiles, a0, f);
  return a0 == a ? 1.0 - f : (a0 + 1u == a ? f : 0.0);
}
// Pixels whose cell touches node index a: [first, last).
uvec2 axis_support(uint size, uint a) {
  int lo = int(floor(float(int(a) - 1) * float(size) / float(pc.tiles))) - 1;
  int hi = int(ceil(float(a + 1u) * float(size) / float(pc.tiles))) + 1;
  return uvec2(clamp(lo, 0, int(size)), clamp(hi, 0, int(size)));
}

void main() {
  const uint s = pc.tiles + 1u, nodes = s * s;
  uint group = evf_linear_group();
  uint p = group / nodes, node = group % nodes;  // p: the interval
  uint a = node % s, b = node / s;
  uvec2 xs = axis_support(pc.width, a), ys = axis_support(pc.height, b);
  uint w = xs.y - xs.x, count = w * (ys.y - ys.x);
  vec2 g = vec2(0.0);
  if (p < pc.intervals) {
    for (uint i = gl_LocalInvocationIndex; i < count; i += kFlowGroupSize) {
      uint x = xs.x + i % w, y = ys.x + i / w;
      float weight = axis_weight(x, pc.width, a) * axis_weight(y, pc.height, b);
      g += weight * grad_field[(p * pc.height + y) * pc.width + x];
    }
  }
  const vec2 total = evf_group_sum(g);
  if (gl_LocalInvocationIndex == 0u && p < pc.intervals) node_grad[p * nodes + node] = total;
}
