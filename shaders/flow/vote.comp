#version 450
// Images of warped events: one invocation per pixel votes each of the pixel's events, warped
// along the piecewise-constant flow to the three reference times, bilinearly into the three IWEs
// (fixed point, integer atomics: exact and order-independent).
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowVoteBindPixelFirst) readonly buffer PixelFirst { uint pixel_first[]; };
layout(std430, binding = kFlowVoteBindEventTime) readonly buffer EventTime { float event_time[]; };
layout(std430, binding = kFlowVoteBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowVoteBindNodes) readonly buffer Nodes { vec2 nodes[]; };
layout(std430, binding = kFlowVoteBindIwe) buffer Iwe { uint iwe[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return nodes[i]; }
#include "flow/flow_math.glsl"

void vote(uint image, ivec2 i0, vec2 f) {
  const uint hw = pc.image_width * pc.image_height;
  for (uint c = 0u; c < 4u; ++c) {
    ivec2 q = i0 + ivec2(c & 1u, c >> 1u);
    if (q.x < 0 || q.y < 0 || q.x >= int(pc.image_width) || q.y >= int(pc.image_height)) continue;
    float w = ((c & 1u) != 0u ? f.x : 1.0 - f.x) * ((c >> 1u) != 0u ? f.y : 1.0 - f.y);
    uint v = uint(w * kFlowVoteScale + 0.5);
    if (v != 0u) atomicAdd(iwe[image * hw + uint(q.y) * pc.image_width + uint(q.x)], v);
  }
}

void main() {
  const uint hw = pc.width * pc.height;
  uint pixel = evf_linear_invocation(kFlowGroupSize);
  if (pixel >= hw) return;
  uint first = pixel_first[pixel], last = pixel_first[pixel + 1u];
  if (first == last) return;
  uint x = pixel % pc.width, y = pixel / pc.width;
  vec2 u[kFlowMaxIntervals];
  for (uint j = 0u; j < pc.intervals; ++j) u[j] = flow_at(j, pc.tiles, pc.width, pc.height, x, y);
  vec2 c = vec2(x, y) + 0.5;
  for (uint e = first; e < last; ++e) {
    float t = event_time[e];
    for (uint r = 0u; r < kFlowRefs; ++r) {
      vec2 d = vec2(0.0);
      for (uint j = 0u; j < pc.intervals; ++j) d += flow_lever(intervals[j], t, flow_ref_time(r)) * u[j];
      ivec2 i0;
      vec2 f;
      flow_footprint((c + d) / pc.scale, i0, f);
      vote(r, i0, f);
    }
  }
}
