#version 450
// Planar float RGB [3][H][W] (linear) -> packed 8-bit RGBA, one uint per pixel, row-major:
// each channel clamped to [0, 1], sRGB-encoded (IEC 61966-2-1) and rounded; alpha 255. Bytes in
// memory are R,G,B,A, or B,G,R,A when pc.bgr != 0 (to match a B8G8R8A8 swapchain image).
#extension GL_GOOGLE_include_directive : require
#include "common/dispatch.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Rgb { float rgb[]; };
layout(std430, binding = 1) writeonly buffer Packed { uint packed_px[]; };
layout(push_constant) uniform PC {
  uint width;
  uint height;
  uint bgr;
} pc;

float encode_srgb(float v) {
  v = isnan(v) ? 0.0 : clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? v * 12.92 : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

uint to_byte(float v) { return uint(clamp(floor(encode_srgb(v) * 255.0 + 0.5), 0.0, 255.0)); }

void main() {
  uint i = evf_linear_invocation(256u);
  uint n = pc.width * pc.height;
  if (i >= n) return;
  uint r = to_byte(rgb[i]), g = to_byte(rgb[n + i]), b = to_byte(rgb[2u * n + i]);
  if (pc.bgr != 0u) { uint t = r; r = b; b = t; }
  packed_px[i] = r | (g << 8) | (b << 16) | (255u << 24);
}
