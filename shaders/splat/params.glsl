// The Gaussian parameter buffers (bindings 0..7), shared by project and project_bwd (which
// defines EVF_PARAMS_NO_SH: it declares only bindings 0..3).
// SH coefficients are split by band so that no single binding exceeds the device's storage
// range sooner than needed: band l holds (2l+1) coefficients x 3 channels per Gaussian.
layout(std430, binding = kParamBindMeans) readonly buffer Means { float means[]; };                   // [N][3]
layout(std430, binding = kParamBindLogScales) readonly buffer LogScales { float log_scales[]; };      // [N][3]
layout(std430, binding = kParamBindQuats) readonly buffer Quats { vec4 quats[]; };                    // [N] wxyz
layout(std430, binding = kParamBindOpacities) readonly buffer Opacities { float opacity_logits[]; };  // [N]
#ifndef EVF_PARAMS_NO_SH  // project_bwd reads the colours project computed, not the bands
// Packed floats read as vec4s (load_sh_all): [N][1][3], [N][3][3], [N][5][3], [N][7][3].
layout(std430, binding = kParamBindSh0) readonly buffer Sh0 { vec4 sh0[]; };
layout(std430, binding = kParamBindSh1) readonly buffer Sh1 { vec4 sh1[]; };
layout(std430, binding = kParamBindSh2) readonly buffer Sh2 { vec4 sh2[]; };
layout(std430, binding = kParamBindSh3) readonly buffer Sh3 { vec4 sh3[]; };
#endif

// Every access below uses constant indices and no data-dependent branch: CPU drivers (lavapipe)
// run both sides of an if and turn each buffer access into a loop over the SIMD lanes, so a
// generic "coefficient k" accessor would touch every band for every k.
vec3 load_mean(uint g) { return vec3(means[3 * g], means[3 * g + 1], means[3 * g + 2]); }
vec3 load_log_scale(uint g) { return vec3(log_scales[3 * g], log_scales[3 * g + 1], log_scales[3 * g + 2]); }
vec4 load_quat(uint g) { return quats[g]; }

#ifndef EVF_PARAMS_NO_SH
// The 4 floats from position s of the 8 in (a, b), s < 4, by selects (no per-lane index).
vec4 shift_window(vec4 a, vec4 b, uint s) {
  return s == 0u ? a : s == 1u ? vec4(a.yzw, b.x) : s == 2u ? vec4(a.zw, b.xy) : vec4(a.w, b.xyz);
}

// u[k] = floats [f + 4k, f + 4k + 4), k < K, of the packed floats of `buf`, a vec4 array whose
// last element is `last`: K + 1 whole vec4 reads from the one holding float f (clamped to `last`:
// the floats kept always lie before the end), shifted by f % 4. On CPU drivers each read is a
// loop over the SIMD lanes whatever its width, so this takes a third of the reads of one float at
// a time.
#define EVF_READ_FLOATS(buf, f, K, last, u)                                        \
  vec4 u[K + 1];                                                                   \
  {                                                                                \
    uint v_ = (f) >> 2u, s_ = (f) & 3u;                                            \
    for (uint k_ = 0u; k_ <= K; ++k_) u[k_] = buf[min(v_ + k_, last)];            \
    for (uint k_ = 0u; k_ < K; ++k_) u[k_] = shift_window(u[k_], u[k_ + 1u], s_); \
  }

// All 16 SH coefficients of Gaussian g of n; bands above `degree` (the buffers' degree) are zero.
void load_sh_all(uint g, uint n, uint degree, out vec3 c[16]) {
  for (int k = 1; k < 16; ++k) c[k] = vec3(0.0);
  EVF_READ_FLOATS(sh0, 3u * g, 1u, (3u * n - 1u) >> 2u, u0)
  c[0] = u0[0].xyz;
  if (degree >= 1) {
    EVF_READ_FLOATS(sh1, 9u * g, 3u, (9u * n - 1u) >> 2u, u)
    c[1] = u[0].xyz;
    c[2] = vec3(u[0].w, u[1].xy);
    c[3] = vec3(u[1].zw, u[2].x);
  }
  if (degree >= 2) {
    EVF_READ_FLOATS(sh2, 15u * g, 4u, (15u * n - 1u) >> 2u, u)
    c[4] = u[0].xyz;
    c[5] = vec3(u[0].w, u[1].xy);
    c[6] = vec3(u[1].zw, u[2].x);
    c[7] = u[2].yzw;
    c[8] = u[3].xyz;
  }
  if (degree >= 3) {
    EVF_READ_FLOATS(sh3, 21u * g, 6u, (21u * n - 1u) >> 2u, u)
    c[9] = u[0].xyz;
    c[10] = vec3(u[0].w, u[1].xy);
    c[11] = vec3(u[1].zw, u[2].x);
    c[12] = u[2].yzw;
    c[13] = u[3].xyz;
    c[14] = vec3(u[3].w, u[4].xy);
    c[15] = vec3(u[4].zw, u[5].x);
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
