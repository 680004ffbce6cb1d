#version 450
// Flow-upsampled blur: every target's taps for each sub-frame of one interval (train_layout.h,
// UpsamplePC), one invocation per (m, pixel); the forward and the backward read them.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kUpsampleGroupSize) in;
layout(std430, binding = kUpsampleTapsBindFlow) readonly buffer Flow { float flow[]; };
layout(std430, binding = kUpsampleTapsBindTaps) writeonly buffer Taps { float taps[]; };
layout(push_constant) uniform PC { UpsamplePC pc; };
#define EVF_UPSAMPLE_FLOW 1
#include "train/upsample_math.glsl"

void main() {
  uint k = evf_linear_invocation(kUpsampleGroupSize), hw = up_hw();
  if (k >= hw * (pc.upsample - 1u)) return;
  uint m = k / hw + 1u, i = k % hw;
  UpTaps t = up_taps(ivec2(int(i % pc.width), int(i / pc.width)), float(m) / float(pc.upsample));
  uint e = ((pc.interval * (pc.upsample - 1u) + m - 1u) * hw + i) * kUpsampleTapFloats;
  taps[e] = intBitsToFloat(t.q0.x);
  taps[e + 1u] = intBitsToFloat(t.q0.y);
  taps[e + 2u] = t.w.x;
  taps[e + 3u] = t.w.y;
  taps[e + 4u] = t.w.z;
  taps[e + 5u] = t.w.w;
}
