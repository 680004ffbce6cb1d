#version 450
// Flow-upsampled blur, forward (train_layout.h, UpsamplePC): adds scale * sum_m S_m(L_i) into
// the mean, one invocation per pixel (all three channels), from the taps of train/upsample_taps.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kUpsampleGroupSize) in;
layout(std430, binding = kUpsampleBindTaps) readonly buffer Taps { float taps[]; };
layout(std430, binding = kUpsampleBindFrame) readonly buffer Frame { float frame[]; };  // L_i, planar linear RGB
layout(std430, binding = kUpsampleBindMean) buffer Mean { float mean[]; };
layout(push_constant) uniform PC { UpsamplePC pc; };
#define EVF_UPSAMPLE_TAPS 1
#include "train/upsample_math.glsl"

vec3 frame_at(ivec2 q) {
  uint i = uint(q.y) * pc.width + uint(q.x), hw = up_hw();
  return vec3(frame[i], frame[hw + i], frame[2u * hw + i]);
}

void main() {
  uint i = evf_linear_invocation(kUpsampleGroupSize), hw = up_hw();
  if (i >= hw) return;
  ivec2 x = ivec2(int(i % pc.width), int(i / pc.width));
  vec3 acc = vec3(0.0);
  for (uint m = 1u; m < pc.upsample; ++m) {
    UpTaps t = up_load(m, i);
    if (up_no_tap(t)) {
      acc += frame_at(x);
      continue;
    }
    if (t.w.x > 0.0) acc += t.w.x * frame_at(t.q0);
    if (t.w.y > 0.0) acc += t.w.y * frame_at(t.q0 + ivec2(1, 0));
    if (t.w.z > 0.0) acc += t.w.z * frame_at(t.q0 + ivec2(0, 1));
    if (t.w.w > 0.0) acc += t.w.w * frame_at(t.q0 + ivec2(1, 1));
  }
  acc *= pc.scale;
  mean[i] += acc.r;
  mean[hw + i] += acc.g;
  mean[2u * hw + i] += acc.b;
}
