#version 450
// Flow-upsampled blur, backward (train_layout.h, UpsamplePC): frame i's share of the mean's
// gradient, share = g + sum_m S_m^T(g), one invocation per source pixel q gathering from the
// targets within reach of its warped position, through the forward's own taps.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kUpsampleGroupSize) in;
layout(std430, binding = kUpsampleBwdBindFlow) readonly buffer Flow { float flow[]; };
layout(std430, binding = kUpsampleBwdBindTaps) readonly buffer Taps { float taps[]; };
layout(std430, binding = kUpsampleBwdBindGrad) readonly buffer Grad { float grad[]; };  // d/d(mean), already / (2NM+1)
layout(std430, binding = kUpsampleBwdBindShare) writeonly buffer Share { float share[]; };
layout(push_constant) uniform PC { UpsamplePC pc; };
#define EVF_UPSAMPLE_FLOW 1
#define EVF_UPSAMPLE_TAPS 1
#include "train/upsample_math.glsl"

vec3 grad_at(ivec2 x) {
  uint i = uint(x.y) * pc.width + uint(x.x), hw = up_hw();
  return vec3(grad[i], grad[hw + i], grad[2u * hw + i]);
}

void main() {
  uint i = evf_linear_invocation(kUpsampleGroupSize), hw = up_hw();
  if (i >= hw) return;
  ivec2 q = ivec2(int(i % pc.width), int(i / pc.width));
  vec3 acc = grad_at(q);
  for (uint m = 1u; m < pc.upsample; ++m) {
    if (up_no_tap(up_load(m, i))) acc += grad_at(q);  // q without taps keeps its own value
    ivec2 c = up_centre(q, float(m) / float(pc.upsample));
    for (int dy = -kUpsampleReach; dy <= kUpsampleReach; ++dy)
      for (int dx = -kUpsampleReach; dx <= kUpsampleReach; ++dx) {
        ivec2 x = c + ivec2(dx, dy);
        if (!up_inside(x)) continue;
        float w = up_weight_of(up_load(m, uint(x.y) * pc.width + uint(x.x)), q);
        if (w > 0.0) acc += w * grad_at(x);
      }
  }
  share[i] = acc.r;
  share[hw + i] = acc.g;
  share[2u * hw + i] = acc.b;
}
