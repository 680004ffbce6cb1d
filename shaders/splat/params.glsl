// The Gaussian parameter buffers (bindings 0..7), shared by project and project_bwd (which
// defines EVF_PARAMS_NO_SH: it declares only bindings 0..3).
// SH coefficients are split by band so that no single binding exceeds the device's storage
// range sooner than needed: band l holds (2l+1) coefficients x 3 channels per Gaussian.
layout(std430, binding = kParamBindMeans) readonly buffer Means { float means[]; };                   // [N][3]
layout(std430, binding = kParamBindLogScales) readonly buffer LogScales { float log_scales[]; };      // [N][3]
layout(std430, binding = kParamBindQuats) readonly buffer Quats { vec4 quats[]; };                    // [N] wxyz
layout(std430, binding = kParamBindOpacities) readonly buffer Opacities { float opacity_logits[]; };  // [N]
#ifndef EVF_PARAMS_NO_SH  // project_bwd reads the colours project computed, not the bands
layout(std430, binding = kParamBindSh0) readonly buffer Sh0 { float sh0[]; };  // [N][1][3]
layout(std430, binding = kParamBindSh1) readonly buffer Sh1 { float sh1[]; };  // [N][3][3]
layout(std430, binding = kParamBindSh2) readonly buffer Sh2 { float sh2[]; };  // [N][5][3]
layout(std430, binding = kParamBindSh3) readonly buffer Sh3 { float sh3[]; };  // [N][7][3]
#endif

// Every access below uses constant indices and no data-dependent branch: CPU drivers (lavapipe)
// run both sides of an if and turn each buffer access into a loop over the SIMD lanes, so a
// generic "coefficient k" accessor would touch every band for every k.
vec3 load_mean(uint g) { return vec3(means[3 * g], means[3 * g + 1], means[3 * g + 2]); }
vec3 load_log_scale(uint g) { return vec3(log_scales[3 * g], log_scales[3 * g + 1], log_scales[3 * g + 2]); }
vec4 load_quat(uint g) { return quats[g]; }

#ifndef EVF_PARAMS_NO_SH
// All 16 SH coefficients of Gaussian g; bands above `degree` (the buffers' degree) are zero.
void load_sh_all(uint g, uint degree, out vec3 c[16]) {
  c[0] = vec3(sh0[3 * g], sh0[3 * g + 1], sh0[3 * g + 2]);
  for (int k = 1; k < 16; ++k) c[k] = vec3(0.0);
  if (degree >= 1) {
    uint i = g * 9;
    c[1] = vec3(sh1[i], sh1[i + 1], sh1[i + 2]);
    c[2] = vec3(sh1[i + 3], sh1[i + 4], sh1[i + 5]);
    c[3] = vec3(sh1[i + 6], sh1[i + 7], sh1[i + 8]);
  }
  if (degree >= 2) {
    uint i = g * 15;
    c[4] = vec3(sh2[i], sh2[i + 1], sh2[i + 2]);
    c[5] = vec3(sh2[i + 3], sh2[i + 4], sh2[i + 5]);
    c[6] = vec3(sh2[i + 6], sh2[i + 7], sh2[i + 8]);
    c[7] = vec3(sh2[i + 9], sh2[i + 10], sh2[i + 11]);
    c[8] = vec3(sh2[i + 12], sh2[i + 13], sh2[i + 14]);
  }
  if (degree >= 3) {
    uint i = g * 21;
    c[9] = vec3(sh3[i], sh3[i + 1], sh3[i + 2]);
    c[10] = vec3(sh3[i + 3], sh3[i + 4], sh3[i + 5]);
    c[11] = vec3(sh3[i + 6], sh3[i + 7], sh3[i + 8]);
    c[12] = vec3(sh3[i + 9], sh3[i + 10], sh3[i + 11]);
    c[13] = vec3(sh3[i + 12], sh3[i + 13], sh3[i + 14]);
    c[14] = vec3(sh3[i + 15], sh3[i + 16], sh3[i + 17]);
    c[15] = vec3(sh3[i + 18], sh3[i + 19], sh3[i + 20]);
  }
}
#endif

// base + sum_k Y[k] c[k], summed in order k = 0..15, written out (constant indices).
vec3 sh_eval(vec3 base, float Y[16], vec3 c[16]) {
  vec3 r = base;
  r += Y[0] * c[0]; r += Y[1] * c[1]; r += Y[2] * c[2]; r += Y[3] * c[3];
  r += Y[4] * c[4]; r += Y[5] * c[5]; r += Y[6] * c[6]; r += Y[7] * c[7];
  r += Y[8] * c[8]; r += Y[9] * c[9]; r += Y[10] * c[10]; r += Y[11] * c[11];
  r += Y[12] * c[12]; r += Y[13] * c[13]; r += Y[14] * c[14]; r += Y[15] * c[15];
  return r;
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
