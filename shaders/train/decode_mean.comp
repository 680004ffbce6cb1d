#version 450
// The image model's forward over an exposure in one pass (train/decode_mean_f<F>, one build per
// frame count F = EVF_FRAME_COUNT; train_layout.h): Y_k = decode(X_k) for every frame k and
// Mean = sum over k of scale * Y_k, added in frame order from zero as train/colour_decode_mean
// adds it a frame per pass (the same values). Where those F passes store and read the mean F times,
// this stores it once: on lavapipe every storage access is a loop over the lanes. Four elements
// per invocation (vec4 accesses), one by one only for the last 1-3; inputs read as texels.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
#include "common/srgb.glsl"
#include "common/frame_list.glsl"
layout(local_size_x = kColourGroupSize) in;
layout(std430, binding = kDecodeMeanBindMean) writeonly buffer Mean { vec4 mean[]; };
#define EVF_FRAME_BINDINGS(k)                                 \
  layout(binding = kDecodeMeanBindX##k) uniform samplerBuffer X##k; \
  layout(std430, binding = kDecodeMeanBindY##k) writeonly buffer Y##k { vec4 y##k[]; };
EVF_FRAMES(EVF_FRAME_BINDINGS)
layout(push_constant) uniform PC { ColourPC pc; };

vec4 decode4(vec4 v) {
  return vec4(evf_srgb_decode(v.x), evf_srgb_decode(v.y), evf_srgb_decode(v.z), evf_srgb_decode(v.w));
}

#define EVF_QUAD(k)                           \
  {                                           \
    vec4 r = decode4(texelFetch(X##k, int(i))); \
    y##k[i] = r;                              \
    m = m + pc.scale * r;                     \
  }
#define EVF_ONE(k)                                           \
  {                                                          \
    float r = evf_srgb_decode(texelFetch(X##k, int(i))[c]); \
    y##k[i][c] = r;                                          \
    m = m + pc.scale * r;                                    \
  }

// The sums are `precise`: without it the compiler may factor scale out of them (scale * (r0 + r1
// ...)), which rounds differently from the per-frame passes.
void main() {
  uint i = evf_linear_invocation(kColourGroupSize);
  if (i * 4u >= pc.n) return;
  if (i * 4u + 4u <= pc.n) {
    precise vec4 m = vec4(0.0);
    EVF_FRAMES(EVF_QUAD)
    mean[i] = m;
    return;
  }
  for (uint c = 0u; i * 4u + c < pc.n; ++c) {
    precise float m = 0.0;
    EVF_FRAMES(EVF_ONE)
    mean[i][c] = m;
  }
}
