#version 450
// Gradient of the loss with respect to each interval's flow at each pixel, one invocation per
// pixel: for each of the pixel's events and each reference r, the derivative of its bilinear vote
// against the adjoint image A_r (which already holds dLoss/dIWE_r), times the event's lever in
// each interval. Gathers, no atomics: reproducible.
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowGradBindPixelFirst) readonly buffer PixelFirst { uint pixel_first[]; };
layout(std430, binding = kFlowGradBindEventTime) readonly buffer EventTime { float event_time[]; };
layout(std430, binding = kFlowGradBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowGradBindNodes) readonly buffer Nodes { vec2 nodes[]; };
layout(std430, binding = kFlowGradBindAdjoint) readonly buffer Adjoint { float adjoint[]; };
layout(std430, binding = kFlowGradBindGradField) writeonly buffer GradField { vec2 grad_field[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return nodes[i]; }
#include "flow/flow_math.glsl"

float adjoint_at(uint image, ivec2 q) {
  if (q.x < 0 || q.y < 0 || q.x >= int(pc.image_width) || q.y >= int(pc.image_height)) return 0.0;
  return adjoint[image * pc.image_width * pc.image_height + uint(q.y) * pc.image_width + uint(q.x)];
}

void main() {
  const uint hw = pc.width * pc.height;
  uint pixel = evf_linear_invocation(kFlowGroupSize);
  if (pixel >= hw) return;
  uint first = pixel_first[pixel], last = pixel_first[pixel + 1u];
  vec2 grad[kFlowMaxIntervals];
  for (uint j = 0u; j < pc.intervals; ++j) grad[j] = vec2(0.0);
  if (first != last) {
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
        vec2 g = (1.0 / pc.scale) * flow_footprint_grad(f, adjoint_at(r, i0), adjoint_at(r, i0 + ivec2(1, 0)),
                                     adjoint_at(r, i0 + ivec2(0, 1)), adjoint_at(r, i0 + ivec2(1, 1)));
        for (uint j = 0u; j < pc.intervals; ++j) grad[j] += flow_lever(intervals[j], t, flow_ref_time(r)) * g;
      }
    }
  }
  for (uint j = 0u; j < pc.intervals; ++j) grad_field[j * hw + pixel] = grad[j];
}
