#version 450
// Gradient of the loss with respect to each interval's flow at each pixel with events (the
// others are zero: the host clears them), one invocation per such pixel, busiest first: for each
// of the pixel's events and each reference r, the derivative of its bilinear vote against the
// adjoint image A_r (which already holds dLoss/dIWE_r), chained through the positions P(t_r) and
// P(t_k) to the cumulative flows and from them to each interval's flow. Gathers, no atomics:
// reproducible.
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowGradBindPixelOrder) readonly buffer PixelOrder { uint pixel_order[]; };
layout(std430, binding = kFlowGradBindPixelFirst) readonly buffer PixelFirst { uint pixel_first[]; };
layout(std430, binding = kFlowGradBindEventTime) readonly buffer EventTime { float event_time[]; };
layout(std430, binding = kFlowGradBindIntervals) readonly buffer Intervals { vec4 intervals[]; };
layout(std430, binding = kFlowGradBindNodes) readonly buffer Nodes { vec2 nodes[]; };
layout(std430, binding = kFlowGradBindAdjoint) readonly buffer Adjoint { float adjoint[]; };
layout(std430, binding = kFlowGradBindGradField) writeonly buffer GradField { vec2 grad_field[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return nodes[i]; }
#define FLOW_INTERVALS 1
#include "flow/flow_math.glsl"

float adjoint_at(uint image, ivec2 q) {
  if (q.x < 0 || q.y < 0 || q.x >= int(pc.image_width) || q.y >= int(pc.image_height)) return 0.0;
  return adjoint[image * pc.image_width * pc.image_height + uint(q.y) * pc.image_width + uint(q.x)];
}

// Adds w * g to the gradient of the cumulative flows at position (i, f): (1 - f) to C_i, f to C_i+1.
void add_at(inout vec2 gc[kFlowMaxIntervals + 1u], uint i, float f, vec2 g) {
  gc[i] += (1.0 - f) * g;
  gc[i + 1u] += f * g;
}

void main() {
  const uint hw = pc.width * pc.height;
  uint k = evf_linear_invocation(kFlowGroupSize);
  if (k >= pc.busy) return;
  uint pixel = pixel_order[k];
  uint first = pixel_first[pixel], last = pixel_first[pixel + 1u];
  uint x = pixel % pc.width, y = pixel / pc.width;
  vec2 C[kFlowMaxIntervals + 1u], gc[kFlowMaxIntervals + 1u];
  C[0] = vec2(0.0);
  gc[0] = vec2(0.0);
  for (uint j = 0u; j < pc.intervals; ++j) {
    C[j + 1u] = C[j] + flow_at(j, pc.tiles, pc.width, pc.height, x, y);
    gc[j + 1u] = vec2(0.0);
  }
  vec2 ref[kFlowRefs], gref[kFlowRefs];
  for (uint r = 0u; r < kFlowRefs; ++r) {
    uint i = 0u;
    float f = flow_interval_fraction(flow_ref_time(r), pc.intervals, i);
    ref[r] = mix(C[i], C[i + 1u], f);
    gref[r] = vec2(0.0);
  }
  vec2 c = vec2(x, y) + 0.5;
  uint i = 0u;
  for (uint e = first; e < last; e += pc.stride) {
    float f = flow_interval_fraction(event_time[e], pc.intervals, i);
    vec2 at = c - mix(C[i], C[i + 1u], f);
    vec2 sum = vec2(0.0);
    for (uint r = 0u; r < kFlowRefs; ++r) {
      ivec2 i0;
      vec2 fr;
      flow_footprint((at + ref[r]) / pc.scale, i0, fr);
      vec2 g = (1.0 / pc.scale) * flow_footprint_grad(fr, adjoint_at(r, i0), adjoint_at(r, i0 + ivec2(1, 0)),
                                                      adjoint_at(r, i0 + ivec2(0, 1)), adjoint_at(r, i0 + ivec2(1, 1)));
      gref[r] += g;
      sum += g;
    }
    add_at(gc, i, f, -sum);
  }
  for (uint r = 0u; r < kFlowRefs; ++r) {
    uint ir = 0u;
    float f = flow_interval_fraction(flow_ref_time(r), pc.intervals, ir);
    add_at(gc, ir, f, gref[r]);
  }
  // C_m = u_0 + ... + u_{m-1}: dLoss/du_j = sum over m > j of dLoss/dC_m.
  vec2 suffix = vec2(0.0);
  for (uint j = pc.intervals; j > 0u; --j) {
    suffix += gc[j];
    grad_field[(j - 1u) * hw + pixel] = suffix;
  }
}
