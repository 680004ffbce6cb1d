#version 450
// The flow gradient reads, for each warped event and reference, the four adjoint values under
// its bilinear footprint. This gathers them once per footprint position: quads[image][qy][qx] =
// (A(i0), A(i0 + (1,0)), A(i0 + (0,1)), A(i0 + (1,1))) for top-left pixel i0 = (qx - 1, qy - 1),
// zero outside the image, over (width + 1) x (height + 1) positions: one vec4 read per footprint.
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowQuadsBindAdjoint) readonly buffer Adjoint { float adjoint[]; };
layout(std430, binding = kFlowQuadsBindQuads) writeonly buffer Quads { vec4 quads[]; };
layout(push_constant) uniform PC { FlowQuadsPC pc; };

float adjoint_at(uint image, ivec2 q) {
  if (q.x < 0 || q.y < 0 || q.x >= int(pc.width) || q.y >= int(pc.height)) return 0.0;
  return adjoint[image * pc.width * pc.height + uint(q.y) * pc.width + uint(q.x)];
}

void main() {
  const uint qw = pc.width + 1u, qhw = qw * (pc.height + 1u);
  uint id = evf_linear_invocation(kFlowGroupSize);
  if (id >= qhw * pc.images) return;
  uint image = id / qhw, q = id % qhw;
  ivec2 i0 = ivec2(q % qw, q / qw) - 1;
  quads[id] = vec4(adjoint_at(image, i0), adjoint_at(image, i0 + ivec2(1, 0)), adjoint_at(image, i0 + ivec2(0, 1)),
                   adjoint_at(image, i0 + ivec2(1, 1)));
}
