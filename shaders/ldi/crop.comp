#version 450
// A crop of a planar image (ldi_layout.h, LdiCropPC): out[c][y][x] = full[c][crop_y + y][crop_x + x].
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiCropBindFull) readonly buffer Full { float full[]; };
layout(std430, binding = kLdiCropBindOut) writeonly buffer Out { float outv[]; };
layout(push_constant) uniform PC { LdiCropPC pc; };

void main() {
  uint i = evf_linear_invocation(kLdiGroupSize), hw = pc.crop_w * pc.crop_h;
  if (i >= pc.channels * hw) return;
  uint c = i / hw, p = i - c * hw, y = p / pc.crop_w, x = p - y * pc.crop_w;
  outv[i] = full[(c * pc.height + pc.crop_y + y) * pc.width + pc.crop_x + x];
}
