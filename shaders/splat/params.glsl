// The Gaussian parameter buffers (bindings 0..7), shared by project and project_bwd (which
// defines EVF_PARAMS_NO_SH: it declares only bindings 0..3).
// SH coefficients are split by band so that no single binding exceeds the device's storage
// range sooner than needed: band l holds (2l+1) coefficients x 3 channels per Gaussian.
// Scalar block layout (a vec3 array's stride is 12 bytes): the packed [N][3] rows are read one vec3
// at a time. On CPU drivers every buffer access is a loop over the SIMD lanes whatever its width,
// so one vec3 access costs what one float does.
#ifdef EVF_PARAM_TEXELS
#ifndef EVF_PARAMS_NO_SH
#error the texel build reads no SH bands: project_bwd's "_block" builds only
#endif
#include "common/texel.glsl"
// project_bwd's "_block" builds (CPU drivers, beside the block compositing kernels) read the
// parameters as RGBA32F texel buffers (why: common/texel.glsl). A packed triple is read as the one
// or two texels it spans (the second index clamped to the view, where a triple that fits in one
// texel ignores it).
layout(binding = kParamBindMeans) uniform samplerBuffer Means;          // [N][3]
layout(binding = kParamBindLogScales) uniform samplerBuffer LogScales;  // [N][3]
layout(binding = kParamBindQuats) uniform samplerBuffer Quats;          // [N] wxyz
layout(binding = kParamBindOpacities) uniform samplerBuffer Opacities;  // [N]
vec3 param_vec3(samplerBuffer b, uint i) {
  uint f = 3u * i, t = f >> 2u;
  vec4 lo = texelFetch(b, int(t)), hi = texelFetch(b, min(int(t) + 1, textureSize(b) - 1));
  uint o = f & 3u;
  return o == 0u ? lo.xyz : o == 1u ? lo.yzw : o == 2u ? vec3(lo.zw, hi.x) : vec3(lo.w, hi.xy);
}
vec3 load_mean(uint g) { return param_vec3(Means, g); }
vec3 load_log_scale(uint g) { return param_vec3(LogScales, g); }
vec4 load_quat(uint g) { return texelFetch(Quats, int(g)); }
float load_opacity_logit(uint g) { return evf_texel_float(Opacities, g); }
#else
layout(scalar, binding = kParamBindMeans) readonly buffer Means { vec3 means[]; };                   // [N]
layout(scalar, binding = kParamBindLogScales) readonly buffer LogScales { vec3 log_scales[]; };      // [N]
layout(std430, binding = kParamBindQuats) readonly buffer Quats { vec4 quats[]; };                    // [N] wxyz
layout(std430, binding = kParamBindOpacities) readonly buffer Opacities { float opacity_logits[]; };  // [N]
vec3 load_mean(uint g) { return means[g]; }
vec3 load_log_scale(uint g) { return log_scales[g]; }
vec4 load_quat(uint g) { return quats[g]; }
float load_opacity_logit(uint g) { return opacity_logits[g]; }
#ifndef EVF_PARAMS_NO_SH  // project_bwd reads the colours project computed, not the bands
// One vec3 (a coefficient's rgb) per access: [N][1], [N][3], [N][5], [N][7].
layout(scalar, binding = kParamBindSh0) readonly buffer Sh0 { vec3 sh0[]; };
layout(scalar, binding = kParamBindSh1) readonly buffer Sh1 { vec3 sh1[]; };
layout(scalar, binding = kParamBindSh2) readonly buffer Sh2 { vec3 sh2[]; };
layout(scalar, binding = kParamBindSh3) readonly buffer Sh3 { vec3 sh3[]; };
#endif
#endif

// Every access below uses constant indices and no data-dependent branch: CPU drivers (lavapipe)
// run both sides of an if and turn each buffer access into a loop over the SIMD lanes, so a
// generic "coefficient k" accessor would touch every band for every k.
#ifndef EVF_PARAMS_NO_SH
// All 16 SH coefficients of Gaussian g; bands above `degree` (at most the buffers' degree) are zero.
void load_sh_all(uint g, uint degree, out vec3 c[16]) {
  for (int k = 1; k < 16; ++k) c[k] = vec3(0.0);
  c[0] = sh0[g];
  if (degree >= 1)
    for (uint k = 0u; k < 3u; ++k) c[1u + k] = sh1[3u * g + k];
  if (degree >= 2)
    for (uint k = 0u; k < 5u; ++k) c[4u + k] = sh2[5u * g + k];
  if (degree >= 3)
    for (uint k = 0u; k < 7u; ++k) c[9u + k] = sh3[7u * g + k];
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
