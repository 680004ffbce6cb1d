#version 450
// The adjoint of ldi/crop (ldi_layout.h, LdiCropPC): full[c][crop_y + y][crop_x + x] += out[c][y][x].
#extension GL_GOOGLE_include_directive : require
#include "ldi/ldi_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLdiGroupSize) in;
layout(std430, binding = kLdiCropBindFull) buffer Full { float full[]; };
layout(std430, binding = kLdiCropBindOut) readonly buffer Out { float outv[]; };
layout(push_constant) uniform PC { LdiCropPC pc; };

void main() {
  uint i = evf_linear_invocation(kLdiGroupSize), hw = pc.crop_w * pc.crop_h;
  if (i >= pc.channels * hw) return;
  uint c = i / hw, p = i - c * hw, y = p / pc.crop_w, x = p - y * pc.crop_w;
  full[(c * pc.height + pc.crop_y + y) * pc.width + pc.crop_x + x] += outv[i];
}
