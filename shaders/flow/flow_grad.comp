#version 450
// Gradient of the loss with respect to each interval's flow at each pixel with events (the
// others are zero: the host clears them), one invocation per such pixel, busiest first: for each
// of the pixel's events and each reference r, the derivative of its bilinear vote against the
// adjoint image A_r (which already holds dLoss/dIWE_r; read as flow/adjoint_quads' footprints), chained through the positions P(t_r) and
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
layout(std430, binding = kFlowGradBindPositions) readonly buffer Positions { vec2 positions[]; };
layout(std430, binding = kFlowGradBindQuads) readonly buffer Quads { vec4 quads[]; };
layout(std430, binding = kFlowGradBindGradField) buffer GradField { vec2 grad_field[]; };
layout(push_constant) uniform PC { FlowEventsPC pc; };
vec2 flow_node(uint i) { return vec2(0.0); }
#define FLOW_INTERVALS 1
#include "flow/flow_math.glsl"

// The four adjoint values under the footprint whose top-left pixel is i0 (flow/adjoint_quads).
vec4 adjoint_quad(uint image, ivec2 i0) {
  const uint qw = pc.image_width + 1u;
  ivec2 q = i0 + 1;
  if (q.x < 0 || q.y < 0 || q.x > int(pc.image_width) || q.y > int(pc.image_height)) return vec4(0.0);
  return quads[(image * (pc.image_height + 1u) + uint(q.y)) * qw + uint(q.x)];
}

void main() {
  const uint hw = pc.width * pc.height;
  uint k = evf_linear_invocation(kFlowGroupSize);
  if (k >= pc.busy) return;
  uint pixel = pixel_order[k];
  uint first = pixel_first[pixel], last = pixel_first[pixel + 1u];
  uint x = pixel % pc.width, y = pixel / pc.width;
  vec2 ref[kFlowRefs], gref[kFlowRefs];
  uint ir[kFlowRefs];
  float fr[kFlowRefs];
  for (uint r = 0u; r < kFlowRefs; ++r) {
    ir[r] = 0u;
    fr[r] = flow_interval_fraction(flow_ref_time(r), pc.intervals, ir[r]);
    ref[r] = positions[(pc.intervals + r) * pc.busy + k];
  }
  for (uint r = 0u; r < kFlowRefs; ++r) gref[r] = vec2(0.0);
  // Slot m - 1 of grad_field first collects dLoss/dC_m (C_0 = 0 is no variable). The event's
  // interval i, C_i and C_i+1, and the gradients against them (g0, g1; carry: C_i's from the
  // events of interval i - 1) stay in registers; C_i's slot is written when the events leave i.
  vec2 c = vec2(x, y) + 0.5;
  uint i = 0u;
  vec4 iv = intervals[0];
  float end = flow_interval_end(0u, pc.intervals);
  vec2 c0 = vec2(0.0), c1 = positions[k];
  vec2 g0 = vec2(0.0), g1 = vec2(0.0), carry = vec2(0.0);
  // Every stride-th event of the exposure, as flow/vote takes them.
  for (uint e = (first + pc.stride - 1u) / pc.stride * pc.stride; e < last; e += pc.stride) {
    const float t = event_time[e];
    while (t >= end) {
      if (i > 0u) grad_field[(i - 1u) * hw + pixel] = g0 + carry;
      carry = g1;
      g0 = g1 = vec2(0.0);
      ++i;
      iv = intervals[i];
      end = flow_interval_end(i, pc.intervals);
      c0 = c1;
      c1 = positions[i * pc.busy + k];
    }
    float f = clamp((t - iv.x) * iv.z, 0.0, 1.0);
    vec2 at = c - mix(c0, c1, f);
    vec2 sum = vec2(0.0);
    for (uint r = 0u; r < kFlowRefs; ++r) {
      ivec2 i0;
      vec2 fq;
      flow_footprint((at + ref[r]) / pc.scale, i0, fq);
      const vec4 a = adjoint_quad(r, i0);
      vec2 g = (1.0 / pc.scale) * flow_footprint_grad(fq, a.x, a.y, a.z, a.w);
      gref[r] += g;
      sum += g;
    }
    g0 -= (1.0 - f) * sum;
    g1 -= f * sum;
  }
  if (i > 0u) grad_field[(i - 1u) * hw + pixel] = g0 + carry;
  grad_field[i * hw + pixel] = g1;
  for (uint m = i + 2u; m <= pc.intervals; ++m) grad_field[(m - 1u) * hw + pixel] = vec2(0.0);
  // The references move with the flows too: (1 - f) of gref to C_ir, f to C_ir+1.
  for (uint r = 0u; r < kFlowRefs; ++r) {
    if (ir[r] > 0u) grad_field[(ir[r] - 1u) * hw + pixel] += (1.0 - fr[r]) * gref[r];
    grad_field[ir[r] * hw + pixel] += fr[r] * gref[r];
  }
  // C_m = u_0 + ... + u_{m-1}: dLoss/du_j = sum over m > j of dLoss/dC_m.
  vec2 suffix = vec2(0.0);
  for (uint j = pc.intervals; j > 0u; --j) {
    suffix += grad_field[(j - 1u) * hw + pixel];
    grad_field[(j - 1u) * hw + pixel] = suffix;
  }
}
