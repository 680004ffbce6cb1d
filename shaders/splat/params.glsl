// The Gaussian parameter buffers (bindings 0..7), shared by project and project_bwd.
// SH coefficients are split by band so that no single binding exceeds the device's storage
// range sooner than needed: band l holds (2l+1) coefficients x 3 channels per Gaussian.
layout(std430, binding = 0) readonly buffer Means { float means[]; };                 // [N][3]
layout(std430, binding = 1) readonly buffer LogScales { float log_scales[]; };        // [N][3]
layout(std430, binding = 2) readonly buffer Quats { float quats[]; };                 // [N][4] wxyz
layout(std430, binding = 3) readonly buffer Opacities { float opacity_logits[]; };    // [N]
layout(std430, binding = 4) readonly buffer Sh0 { float sh0[]; };                     // [N][1][3]
layout(std430, binding = 5) readonly buffer Sh1 { float sh1[]; };                     // [N][3][3]
layout(std430, binding = 6) readonly buffer Sh2 { float sh2[]; };                     // [N][5][3]
layout(std430, binding = 7) readonly buffer Sh3 { float sh3[]; };                     // [N][7][3]

vec3 load_vec3(uint g, uint which) {
  if (which == 0) return vec3(means[3 * g], means[3 * g + 1], means[3 * g + 2]);
  return vec3(log_scales[3 * g], log_scales[3 * g + 1], log_scales[3 * g + 2]);
}
vec4 load_quat(uint g) { return vec4(quats[4 * g], quats[4 * g + 1], quats[4 * g + 2], quats[4 * g + 3]); }

// Coefficient k (0..15) of Gaussian g.
vec3 load_sh(uint g, uint k) {
  if (k == 0) return vec3(sh0[3 * g], sh0[3 * g + 1], sh0[3 * g + 2]);
  if (k < 4) { uint i = (g * 3 + (k - 1)) * 3; return vec3(sh1[i], sh1[i + 1], sh1[i + 2]); }
  if (k < 9) { uint i = (g * 5 + (k - 4)) * 3; return vec3(sh2[i], sh2[i + 1], sh2[i + 2]); }
  uint i = (g * 7 + (k - 9)) * 3;
  return vec3(sh3[i], sh3[i + 1], sh3[i + 2]);
}

Camera camera_from(CameraPC c) {
  Camera cam;
  cam.R = transpose(mat3(c.row0.xyz, c.row1.xyz, c.row2.xyz));
  cam.t = vec3(c.row0.w, c.row1.w, c.row2.w);
  cam.intrin = c.intrin;
  cam.size = vec2(c.width, c.height);
  return cam;
}
vec3 camera_center(Camera cam) { return -(transpose(cam.R) * cam.t); }
