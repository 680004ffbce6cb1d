#version 450
// Planar linear float RGB [3][src_h][src_w] -> a rectangle of the packed canvas, nearest
// neighbour (mapping in view_layout.h, BlitPC). One invocation per rectangle pixel.
#extension GL_GOOGLE_include_directive : require
#include "view/view_layout.h"
#include "view/srgb8.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kViewGroupSize) in;
layout(std430, binding = kBlitRgbBindRgb) readonly buffer Rgb { float rgb[]; };
layout(std430, binding = kBlitRgbBindCanvas) buffer Canvas { uint canvas[]; };
layout(push_constant) uniform PCBlock { BlitPC pc; };

void main() {
  uint i = evf_linear_invocation(kViewGroupSize);
  if (i >= pc.w * pc.h) return;
  uint dx = i % pc.w, dy = i / pc.w;
  uint X = pc.x + dx, Y = pc.y + dy;
  if (X >= pc.canvas_w || Y >= pc.canvas_h) return;
  uint sx = min(((2u * dx + 1u) * pc.src_w) / (2u * pc.w), pc.src_w - 1u);
  uint sy = min(((2u * dy + 1u) * pc.src_h) / (2u * pc.h), pc.src_h - 1u);
  uint n = pc.src_w * pc.src_h, s = sy * pc.src_w + sx;
  canvas[Y * pc.canvas_w + X] = evf_pack_rgb(rgb[s], rgb[n + s], rgb[2u * n + s], pc.bgr);
}
