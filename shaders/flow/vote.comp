#version 450
// Images of warped events: one invocation per pixel with events (busiest first, so that the
// invocations of a SIMD group loop about as long) votes each of the pixel's events, warped along
// the piecewise-constant flow to the three reference times, bilinearly into the three IWEs (fixed
// point, integer atomics: exact and order-independent).
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowVoteBindPixelOrder) readonly buffer PixelOrder { uint pixel_order[]; };
layout(std430, binding = kFlowVoteBindPixelFirst) readonly buffer PixelFirst { uint pixel_first[]; };
layout(std430, binding = kFlowVoteBindEventTime) readonly buffer EventTime { float event_time[]; };
layout(std430, binding = kFlowVoteBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowVoteBindNodes) readonly buffer Nodes { vec2 nodes[]; };
layout(std430, binding = kFlowVoteBindIwe) buffer Iwe { uint iwe[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return nodes[i]; }
#define FLOW_INTERVALS 1
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
  uint k = evf_linear_invocation(kFlowGroupSize);
  if (k >= pc.busy) return;
  uint pixel = pixel_order[k];
  uint first = pixel_first[pixel], last = pixel_first[pixel + 1u];
  uint x = pixel % pc.width, y = pixel / pc.width;
  vec2 C[kFlowMaxIntervals + 1u];
  C[0] = vec2(0.0);
  for (uint j = 0u; j < pc.intervals; ++j) C[j + 1u] = C[j] + flow_at(j, pc.tiles, pc.width, pc.height, x, y);
  vec2 ref[kFlowRefs];
  for (uint r = 0u; r < kFlowRefs; ++r) {
    uint i = 0u;
    float f = flow_interval_fraction(flow_ref_time(r), pc.intervals, i);
    ref[r] = mix(C[i], C[i + 1u], f);
  }
  vec2 c = vec2(x, y) + 0.5;
  uint i = 0u;
  for (uint e = first; e < last; e += pc.stride) {
    float f = flow_interval_fraction(event_time[e], pc.intervals, i);
    vec2 at = c - mix(C[i], C[i + 1u], f);
    for (uint r = 0u; r < kFlowRefs; ++r) {
      ivec2 i0;
      vec2 fr;
      flow_footprint((at + ref[r]) / pc.scale, i0, fr);
      vote(r, i0, fr);
    }
  }
}
