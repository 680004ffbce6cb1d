#version 450
// Density statistics after one backward: per Gaussian, the (scaled) screen-space gradient norm
// and a visibility count; with a camera, also the largest screen radius seen.
#extension GL_GOOGLE_include_directive : require
#include "densify/densify_layout.h"
#include "common/dispatch.glsl"
#include "densify/densify_common.glsl"
layout(local_size_x = kDensifyGroupSize) in;
layout(std430, binding = kDensifyAccumulateBindGrad2d) readonly buffer Grad2d { float grad2d_norm[]; };
layout(std430, binding = kDensifyAccumulateBindMeans) readonly buffer Means { float means[]; };
layout(std430, binding = kDensifyAccumulateBindLogScales) readonly buffer LogScales { float log_scales[]; };
layout(std430, binding = kDensifyAccumulateBindQuats) readonly buffer Quats { vec4 quats[]; };
layout(std430, binding = kDensifyAccumulateBindGradSum) buffer GradSum { float grad_sum[]; };
layout(std430, binding = kDensifyAccumulateBindVisCount) buffer VisCount { uint vis_count[]; };
layout(std430, binding = kDensifyAccumulateBindMaxRadius) buffer MaxRadius { float max_radius[]; };
layout(push_constant) uniform PC { AccumulatePC pc; };

// Screen radius ceil(3 sqrt(lambda_max)) of the dilated EWA covariance (Inria's rule), or -1
// when the Gaussian is behind the near plane, degenerate or off the image.
float screen_radius(uint g) {
  vec3 m = vec3(means[3 * g], means[3 * g + 1], means[3 * g + 2]);
  mat3 Rc = transpose(mat3(pc.cam.row0.xyz, pc.cam.row1.xyz, pc.cam.row2.xyz));  // rows -> matrix
  vec3 tc = vec3(pc.cam.row0.w, pc.cam.row1.w, pc.cam.row2.w);
  vec3 p = Rc * m + tc;
  if (!(p.z >= pc.cam.near_plane && p.z <= pc.cam.far_plane)) return -1.0;
  vec3 s = exp(vec3(log_scales[3 * g], log_scales[3 * g + 1], log_scales[3 * g + 2]));
  mat3 M = Rc * quat_to_mat(quats[g]) * mat3(vec3(s.x, 0, 0), vec3(0, s.y, 0), vec3(0, 0, s.z));
  mat3 S = M * transpose(M);
  vec2 f = pc.cam.intrin.xy;
  vec2 size = vec2(pc.cam.width, pc.cam.height);
  vec2 lim = 1.3 * 0.5 * size / f;
  float u = clamp(p.x / p.z, -lim.x, lim.x), v = clamp(p.y / p.z, -lim.y, lim.y);
  mat3x2 J = mat3x2(vec2(f.x / p.z, 0.0), vec2(0.0, f.y / p.z), vec2(-f.x * u / p.z, -f.y * v / p.z));
  mat2 c = J * S * transpose(J);
  float a = c[0][0] + 0.3, b = c[0][1], d = c[1][1] + 0.3;
  float det = a * d - b * b;
  if (!(det > 0.0)) return -1.0;
  float mid = 0.5 * (a + d);
  float lambda = mid + sqrt(max(0.1, mid * mid - det));
  float r = ceil(3.0 * sqrt(lambda));
  vec2 c2 = vec2(f.x * p.x / p.z + pc.cam.intrin.z, f.y * p.y / p.z + pc.cam.intrin.w);
  if (c2.x + r <= 0.0 || c2.y + r <= 0.0 || c2.x - r >= size.x || c2.y - r >= size.y) return -1.0;
  return r;
}

void main() {
  uint g = evf_linear_invocation(kDensifyGroupSize);
  if (g >= pc.count) return;
  float n = grad2d_norm[g];
  bool visible;
  if (pc.use_camera != 0u) {
    float r = screen_radius(g);
    visible = r >= 0.0;
    if (visible) max_radius[g] = max(max_radius[g], r);
  } else {
    visible = n > 0.0;
  }
  if (visible) {
    if (n == n) grad_sum[g] += n * pc.grad_scale;  // a NaN norm is not accumulated
    vis_count[g] += 1u;
  }
}
