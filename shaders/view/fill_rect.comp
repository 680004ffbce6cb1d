#version 450
// A rectangle of the packed canvas set to one colour (FillPC in view_layout.h).
#extension GL_GOOGLE_include_directive : require
#include "view/view_layout.h"
#include "view/srgb8.glsl"
#include "common/dispatch.glsl"
layout(local_size_x = kViewGroupSize) in;
layout(std430, binding = kFillRectBindCanvas) buffer Canvas { uint canvas[]; };
layout(push_constant) uniform PCBlock { FillPC pc; };

void main() {
  uint i = evf_linear_invocation(kViewGroupSize);
  if (i >= pc.w * pc.h) return;
  uint X = pc.x + i % pc.w, Y = pc.y + i / pc.w;
  if (X >= pc.canvas_w || Y >= pc.canvas_h) return;
  canvas[Y * pc.canvas_w + X] = evf_canvas_rgba(pc.rgba, pc.bgr);
}
