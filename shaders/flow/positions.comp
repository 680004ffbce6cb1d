#version 450
// The positions both event kernels need at each pixel with events (busiest first, index k), once
// per evaluation: the cumulative flows C_1 .. C_J (C_0 = 0) and the content's position at the
// three reference times, P(t_r). positions[m * busy + k]: m < J is C_m+1, m = J + r is P(t_r).
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowPositionsBindPixelOrder) readonly buffer PixelOrder { uint pixel_order[]; };
layout(std430, binding = kFlowPositionsBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowPositionsBindNodes) readonly buffer Nodes { vec2 nodes[]; };
layout(std430, binding = kFlowPositionsBindPositions) writeonly buffer Positions { vec2 positions[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return nodes[i]; }
#define FLOW_INTERVALS 1
#include "flow/flow_math.glsl"

void main() {
  uint k = evf_linear_invocation(kFlowGroupSize);
  if (k >= pc.busy) return;
  uint pixel = pixel_order[k];
  uint x = pixel % pc.width, y = pixel / pc.width;
  uint ir[kFlowRefs];
  float fr[kFlowRefs];
  for (uint r = 0u; r < kFlowRefs; ++r) {
    ir[r] = 0u;
    fr[r] = flow_interval_fraction(flow_ref_time(r), pc.intervals, ir[r]);
  }
  vec2 c0 = vec2(0.0);
  for (uint j = 0u; j < pc.intervals; ++j) {
    vec2 c1 = c0 + flow_at(j, pc.tiles, pc.width, pc.height, x, y);
    positions[j * pc.busy + k] = c1;
    for (uint r = 0u; r < kFlowRefs; ++r)
      if (ir[r] == j) positions[(pc.intervals + r) * pc.busy + k] = mix(c0, c1, fr[r]);
    c0 = c1;
  }
}
