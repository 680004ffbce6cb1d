#version 450
// Gaussian blur (flow_gauss: kFlowBlurSigma, kFlowBlurRadius, zero outside the image) of `images` images along one
// axis. The blur is symmetric, so the same kernel is its own adjoint.
#extension GL_GOOGLE_include_directive : require
#include "flow/flow_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kFlowGroupSize) in;
layout(std430, binding = kFlowBlurBindSrc) readonly buffer Src { uint src[]; };
layout(std430, binding = kFlowBlurBindDst) writeonly buffer Dst { float dst[]; };
layout(push_constant) uniform PC { FlowBlurPC pc; };
vec2 flow_node(uint i) { return vec2(0.0); }
#include "flow/flow_math.glsl"

float read_src(uint i) {
  uint v = src[i];
  return pc.fixed_input != 0u ? float(v) / kFlowVoteScale : uintBitsToFloat(v);
}

void main() {
  const uint hw = pc.width * pc.height;
  uint id = evf_linear_invocation(kFlowGroupSize);
  if (id >= hw * pc.images) return;
  uint image = id / hw, pixel = id % hw;
  int x = int(pixel % pc.width), y = int(pixel / pc.width);
  ivec2 step = pc.axis == 0u ? ivec2(1, 0) : ivec2(0, 1);
  float sum = 0.0;
  for (int d = -kFlowBlurRadius; d <= kFlowBlurRadius; ++d) {
    ivec2 q = ivec2(x, y) + d * step;
    if (q.x < 0 || q.y < 0 || q.x >= int(pc.width) || q.y >= int(pc.height)) continue;
    sum += flow_gauss(d) * read_src(image * hw + uint(q.y) * pc.width + uint(q.x));
  }
  dst[id] = sum;
}
