#version 450
// Per new row: mean and log-scale. Copies take the source row; split children are sampled from
// the parent Gaussian (offset R(q) diag(s) z, z ~ N(0, I) from a per-row hash, truncated to
// max_sigma) with log-scale - log_split_div.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kDensifyGeometryBindMeans) readonly buffer Means { float means[]; };
layout(std430, binding = kDensifyGeometryBindLogScales) readonly buffer LogScales { float log_scales[]; };
layout(std430, binding = kDensifyGeometryBindQuats) readonly buffer Quats { vec4 quats[]; };
layout(std430, binding = kDensifyGeometryBindParamSrc) readonly buffer ParamSrc { uint param_src[]; };
layout(std430, binding = kDensifyGeometryBindCode) readonly buffer Code { uint row_code[]; };
layout(std430, binding = kDensifyGeometryBindNewMeans) writeonly buffer NewMeans { float new_means[]; };
layout(std430, binding = kDensifyGeometryBindNewLogScales) writeonly buffer NewLogScales { float new_log_scales[]; };
layout(push_constant) uniform PC { EmitPC pc; };

void main() {
  uint r = evf_linear_invocation(kDensifyGroupSize);
  if (r >= pc.rows) return;
  uint s = param_src[r];
  uint code = row_code[r];
  vec3 m = vec3(means[3 * s], means[3 * s + 1], means[3 * s + 2]);
  vec3 ls = vec3(log_scales[3 * s], log_scales[3 * s + 1], log_scales[3 * s + 2]);
  if (code != kRowCopy) {
    uint child = code - kRowChild0;
    uint h = pcg_hash(pc.seed ^ pcg_hash(2u * s + child));
    float u[4];
    for (int k = 0; k < 4; ++k) {
      h = pcg_hash(h);
      u[k] = unit_uniform(h);
    }
    const float two_pi = 6.283185307179586;
    float r0 = sqrt(-2.0 * log(u[0])), r1 = sqrt(-2.0 * log(u[2]));
    vec3 z = vec3(r0 * cos(two_pi * u[1]), r0 * sin(two_pi * u[1]), r1 * cos(two_pi * u[3]));
    float len = length(z);
    if (len > pc.max_sigma) z *= pc.max_sigma / len;
    m += quat_to_mat(quats[s]) * (exp(ls) * z);
    ls -= vec3(pc.log_split_div);
  }
  new_means[3 * r] = m.x;
  new_means[3 * r + 1] = m.y;
  new_means[3 * r + 2] = m.z;
  new_log_scales[3 * r] = ls.x;
  new_log_scales[3 * r + 1] = ls.y;
  new_log_scales[3 * r + 2] = ls.z;
}
