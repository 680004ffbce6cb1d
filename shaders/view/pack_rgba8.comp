#version 450
// Planar float RGB [3][H][W] (linear) -> packed 8-bit RGBA, one uint per pixel, row-major:
// each channel clamped to [0, 1], sRGB-encoded (IEC 61966-2-1) and rounded; alpha 255. Bytes in
// memory are R,G,B,A, or B,G,R,A when pc.bgr != 0 (to match a B8G8R8A8 swapchain image).
#extension GL_GOOGLE_include_directive : require
#include "view/view_layout.h"
#include "view/srgb8.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kViewGroupSize) in;
layout(std430, binding = kPackRgba8BindRgb) readonly buffer Rgb { float rgb[]; };
layout(std430, binding = kPackRgba8BindPacked) writeonly buffer Packed { uint packed_px[]; };
layout(push_constant) uniform PCBlock { PackPC pc; };

void main() {
  uint i = evf_linear_invocation(kViewGroupSize);
  uint n = pc.width * pc.height;
  if (i >= n) return;
  packed_px[i] = evf_pack_rgb(rgb[i], rgb[n + i], rgb[2u * n + i], pc.bgr);
}
