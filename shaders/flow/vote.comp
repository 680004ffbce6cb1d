#version 450
// Images of warped events: one invocation per event (every stride-th of the exposure's, in their
// pixel-by-pixel order) votes it, warped along the piecewise-constant flow to the three reference
// times, bilinearly into the three IWEs (fixed point, integer atomics: exact and
// order-independent). Its pixel's cumulative flows and reference positions come from
// flow/positions.
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowVoteBindPixelOrder) readonly buffer PixelOrder { uint pixel_order[]; };
layout(std430, binding = kFlowVoteBindEventSlot) readonly buffer EventSlot { uint event_slot[]; };
layout(std430, binding = kFlowVoteBindEventTime) readonly buffer EventTime { float event_time[]; };
layout(std430, binding = kFlowVoteBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowVoteBindPositions) readonly buffer Positions { vec2 positions[]; };
layout(std430, binding = kFlowVoteBindIwe) buffer Iwe { uint iwe[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return vec2(0.0); }
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
  uint e = evf_linear_invocation(kFlowGroupSize) * pc.stride;
  if (e >= pc.events) return;
  const uint k = event_slot[e], pixel = pixel_order[k];
  const float t = event_time[e];
  const uint i = flow_event_interval(t, pc.intervals);
  const vec4 iv = intervals[i];
  const vec2 c0 = i > 0u ? positions[(i - 1u) * pc.busy + k] : vec2(0.0), c1 = positions[i * pc.busy + k];
  const vec2 at = vec2(pixel % pc.width, pixel / pc.width) + 0.5 - mix(c0, c1, clamp((t - iv.x) * iv.z, 0.0, 1.0));
  for (uint r = 0u; r < kFlowRefs; ++r) {
    ivec2 i0;
    vec2 f;
    flow_footprint((at + positions[(pc.intervals + r) * pc.busy + k]) / pc.scale, i0, f);
    vote(r, i0, f);
  }
}
