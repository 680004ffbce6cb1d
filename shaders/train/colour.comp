#version 450
// Per-element colour conversions of the image model, one build per conversion (EVF_COLOUR_OP,
// train/colour_<op>; a push-constant switch would run every branch's work on CPU drivers):
//   decode:     y = decode(x)             (sRGB render -> linear light)
//   encode:     y = encode(x)             (linear mean -> sRGB, loss_space=srgb)
//   decode_bwd: y = g * decode'(x)        (d/d(linear frame) -> d/d(sRGB render))
//   encode_bwd: y = g * encode'(x)        (d/d(sRGB prediction) -> d/d(linear mean))
//   decode_mean (EVF_COLOUR_MEAN, with decode): also Mean = (accumulate ? Mean : 0) + scale * y,
//               the exposure's mean in the same pass (what train/accumulate adds, bit for bit)
// Four elements per invocation through vec4 accesses (CPU drivers loop over the lanes for every
// storage access), one by one only for the last 1-3; the inputs are read as texels (on lavapipe
// straight-line code, not a loop over the lanes; a buffer is a whole number of vec4s,
// gpu/buffer.h). Forward and backward share shaders/common/srgb.glsl.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
#include "common/srgb.glsl"
#ifndef EVF_COLOUR_OP
#error EVF_COLOUR_OP selects the conversion (train_layout.h: kColourDecode ...)
#endif
layout(local_size_x = kColourGroupSize) in;
layout(binding = kColourBindX) uniform samplerBuffer X;
layout(binding = kColourBindG) uniform samplerBuffer G;
layout(std430, binding = kColourBindY) writeonly buffer Y { vec4 y[]; };
#ifdef EVF_COLOUR_MEAN
// What the mean adds to is read through a texel view of the same buffer (each element read, then
// written, by its own invocation alone): a `+=` on a storage buffer is two loops over the lanes.
layout(std430, binding = kColourBindMean) writeonly buffer Mean { vec4 mean[]; };
layout(binding = kColourBindMeanIn) uniform samplerBuffer MeanIn;
#endif
layout(push_constant) uniform PC { ColourPC pc; };

float convert(float v, float grad) {
#if EVF_COLOUR_OP == 0
  return evf_srgb_decode(v);
#elif EVF_COLOUR_OP == 1
  return evf_srgb_encode(v);
#elif EVF_COLOUR_OP == 2
  return grad * evf_srgb_decode_deriv(v);
#else
  return grad * evf_srgb_encode_deriv(v);
#endif
}

#if EVF_COLOUR_OP >= 2
#define EVF_GRAD(i, c) texelFetch(G, int(i))[c]
#define EVF_GRAD4(i) texelFetch(G, int(i))
#else
#define EVF_GRAD(i, c) 0.0
#define EVF_GRAD4(i) vec4(0.0)
#endif

void main() {
  uint i = evf_linear_invocation(kColourGroupSize);
  if (i * 4u >= pc.n) return;
  if (i * 4u + 4u <= pc.n) {
    vec4 v = texelFetch(X, int(i)), gr = EVF_GRAD4(i);
    vec4 r = vec4(convert(v.x, gr.x), convert(v.y, gr.y), convert(v.z, gr.z), convert(v.w, gr.w));
    y[i] = r;
#ifdef EVF_COLOUR_MEAN
    mean[i] = (pc.accumulate != 0u ? texelFetch(MeanIn, int(i)) : vec4(0.0)) + pc.scale * r;
#endif
    return;
  }
  for (uint c = 0u; i * 4u + c < pc.n; ++c) {
    float r = convert(texelFetch(X, int(i))[c], EVF_GRAD(i, c));
    y[i][c] = r;
#ifdef EVF_COLOUR_MEAN
    mean[i][c] = (pc.accumulate != 0u ? texelFetch(MeanIn, int(i))[c] : 0.0) + pc.scale * r;
#endif
  }
}
