#version 450
// Per-element colour conversions of the image model (ColourPC.op, train_layout.h):
//   kColourDecode:    y = decode(x)             (sRGB render -> linear light)
//   kColourEncode:    y = encode(x)             (linear mean -> sRGB, loss_space=srgb)
//   kColourDecodeBwd: y = g * decode'(x)        (d/d(linear frame) -> d/d(sRGB render))
//   kColourEncodeBwd: y = g * encode'(x)        (d/d(sRGB prediction) -> d/d(linear mean))
// Forward and backward share shaders/common/srgb.glsl.
#extension GL_GOOGLE_include_directive : require
#include "train/train_layout.h"
#include "common/dispatch.glsl"
#include "common/srgb.glsl"
layout(local_size_x = kColourGroupSize) in;
layout(std430, binding = kColourBindX) readonly buffer X { float x[]; };
layout(std430, binding = kColourBindG) readonly buffer G { float g[]; };
layout(std430, binding = kColourBindY) writeonly buffer Y { float y[]; };
layout(push_constant) uniform PC { ColourPC pc; };
void main() {
  uint i = evf_linear_invocation(kColourGroupSize);
  if (i >= pc.n) return;
  const float v = x[i];
  if (pc.op == kColourDecode) y[i] = evf_srgb_decode(v);
  else if (pc.op == kColourEncode) y[i] = evf_srgb_encode(v);
  else if (pc.op == kColourDecodeBwd) y[i] = g[i] * evf_srgb_decode_deriv(v);
  else y[i] = g[i] * evf_srgb_encode_deriv(v);
}
