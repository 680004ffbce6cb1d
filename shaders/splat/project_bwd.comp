#version 450
// Projection backward: one invocation per Gaussian. Sums the Gaussian's intersection slots in
// order (deterministic), then chains v_mean2d, v_conic, v_opacity and v_colour back to its
// parameters, and its share of the camera-pose gradient (se(3), translation first, exact:
// through the camera-space mean, the rotated covariance and the SH view direction), which the
// workgroup reduces to one partial 6-vector.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_scalar_block_layout : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
#include "common/texel.glsl"
layout(local_size_x = kProjectGroupSize) in;
#define EVF_PARAMS_NO_SH
#include "splat/params.glsl"
// Per-slot gradients (splat_layout.h): (v_mean2d.xy, v_conic.xy), (v_conic.z, v_opacity, v_rgb.rg), v_rgb.b.
#ifdef EVF_SLOT_TEXELS
// The "_block" builds (CPU drivers, with the block compositing kernels) read the offsets and the
// slots' gradients as texel buffers (why: common/texel.glsl). The third plane is read four slots
// to a texel (its buffer is a whole number of texels, rasterizer.cpp).
layout(binding = kProjectBwdBindOffsets) uniform usamplerBuffer Offsets;
layout(binding = kProjectBwdBindG0) uniform samplerBuffer G0;
layout(binding = kProjectBwdBindG1) uniform samplerBuffer G1;
layout(binding = kProjectBwdBindG2) uniform samplerBuffer G2;
uint isect_offset_at(uint g) { return texelFetch(Offsets, int(g)).x; }
vec4 slot_grad_a(uint s) { return texelFetch(G0, int(s)); }
vec4 slot_grad_b(uint s) { return texelFetch(G1, int(s)); }
float slot_grad_c(uint s) { return evf_texel_float(G2, s); }
#else
layout(std430, binding = kProjectBwdBindOffsets) readonly buffer Offsets { uint isect_offset[]; };
layout(std430, binding = kProjectBwdBindG0) readonly buffer G0 { vec4 grad_a[]; };
layout(std430, binding = kProjectBwdBindG1) readonly buffer G1 { vec4 grad_b[]; };
layout(std430, binding = kProjectBwdBindG2) readonly buffer G2 { float grad_c[]; };
uint isect_offset_at(uint g) { return isect_offset[g]; }
vec4 slot_grad_a(uint s) { return grad_a[s]; }
vec4 slot_grad_b(uint s) { return grad_b[s]; }
float slot_grad_c(uint s) { return grad_c[s]; }
#endif
// Packed [N][3] rows and SH bands ([N][2l+1] rgb triples) as scalar-layout vec3 arrays: one
// access per triple (on CPU drivers each access is a loop over the SIMD lanes, whatever its width).
layout(scalar, binding = kProjectBwdBindVMeans) buffer VMeans { vec3 v_means[]; };
layout(scalar, binding = kProjectBwdBindVLogScales) buffer VLogScales { vec3 v_log_scales[]; };
layout(std430, binding = kProjectBwdBindVQuats) buffer VQuats { vec4 v_quats[]; };  // [N] wxyz
layout(std430, binding = kProjectBwdBindVOpacities) buffer VOpacities { float v_opacity_logits[]; };
layout(scalar, binding = kProjectBwdBindVSh0) buffer VSh0 { vec3 v_sh0[]; };
layout(scalar, binding = kProjectBwdBindVSh1) buffer VSh1 { vec3 v_sh1[]; };
layout(scalar, binding = kProjectBwdBindVSh2) buffer VSh2 { vec3 v_sh2[]; };
layout(scalar, binding = kProjectBwdBindVSh3) buffer VSh3 { vec3 v_sh3[]; };
layout(std430, binding = kProjectBwdBindGrad2d) buffer Grad2d { float grad2d_norm[]; };
layout(std430, binding = kProjectBwdBindPosePartial) writeonly buffer PosePartial { float pose_partial[]; };  // [groups][6]
// From the forward (project.comp): the clamped colour max(raw, 0) (raw > 0 exactly where it is
// > 0) and d(raw)/d(direction), so that no SH coefficient is read here.
#ifdef EVF_SLOT_TEXELS
layout(binding = kProjectBwdBindProjC) uniform samplerBuffer ProjC;
layout(binding = kProjectBwdBindDColor) uniform samplerBuffer DColor;  // [N][3] (.xyz)
vec3 clamped_color(uint g) { return texelFetch(ProjC, int(g)).rgb; }
vec3 dcolor(uint i) { return texelFetch(DColor, int(i)).xyz; }
#else
layout(std430, binding = kProjectBwdBindProjC) readonly buffer ProjC { vec4 proj_color[]; };
layout(std430, binding = kProjectBwdBindDColor) readonly buffer DColor { vec4 proj_dcolor[]; };  // [N][3] (.xyz)
vec3 clamped_color(uint g) { return proj_color[g].rgb; }
vec3 dcolor(uint i) { return proj_dcolor[i].xyz; }
#endif
#ifdef EVF_FRAMES
layout(push_constant) uniform PC { ProjectFramesPC pc; };
layout(binding = kProjectBwdBindFrames) uniform samplerBuffer Frames;
// Frame f's camera from its texels (the host writes CameraPC as it is laid out).
CameraPC frame_camera(uint f) {
  int t = int(kProjectFrameTexels * f);
  CameraPC c;
  c.row0 = texelFetch(Frames, t);
  c.row1 = texelFetch(Frames, t + 1);
  c.row2 = texelFetch(Frames, t + 2);
  c.intrin = texelFetch(Frames, t + 3);
  vec4 rest = texelFetch(Frames, t + 4);
  c.width = floatBitsToUint(rest.x);
  c.height = floatBitsToUint(rest.y);
  c.near_plane = rest.z;
  c.far_plane = rest.w;
  return c;
}
#else
layout(push_constant) uniform PC { ProjectPC pc; };
#endif

#ifdef EVF_POSE_PER_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#else
shared float red[6][kProjectGroupSize];
#endif

// EVF_FRAMES (the "_frames_block" build, with the "_block" build's texels): every frame of an
// exposure in one pass, each Gaussian's parameters read once and its gradients summed in registers
// in frame order, then stored once (an overwrite); a pose partial per frame and subgroup. The sums
// are those of one pass per frame, the first overwriting and the others adding, in that order.
// EVF_ACCUMULATE (the "_acc" build, kFlagAccumulate): add to the gradient buffers (several
// renders of one step, e.g. the virtual frames of an exposure) instead of overwriting them. A
// build of its own rather than a branch: CPU drivers would run the reads of a branch anyway.
// EVF_PUT1/3/4(buffer, texels, index, value) write a float, a packed triple or a vec4. The
// "_acc_block" build reads the values it adds to through texel views of the same buffers (`texels`:
// each element is read and then written by its own invocation alone), a gather on lavapipe where
// `+=` on a storage buffer is a loop over the lanes to load and another to store.
#if defined(EVF_ACCUMULATE) && defined(EVF_SLOT_TEXELS)
layout(binding = kProjectBwdBindVMeansIn) uniform samplerBuffer VMeansIn;
layout(binding = kProjectBwdBindVLogScalesIn) uniform samplerBuffer VLogScalesIn;
layout(binding = kProjectBwdBindVQuatsIn) uniform samplerBuffer VQuatsIn;
layout(binding = kProjectBwdBindVOpacitiesIn) uniform samplerBuffer VOpacitiesIn;
layout(binding = kProjectBwdBindVSh0In) uniform samplerBuffer VSh0In;
layout(binding = kProjectBwdBindGrad2dIn) uniform samplerBuffer Grad2dIn;
#define EVF_PUT1(buf, tex, i, value) buf[i] = evf_texel_float(tex, i) + (value)
#define EVF_PUT3(buf, tex, i, value) buf[i] = param_vec3(tex, i) + (value)
#define EVF_PUT4(buf, tex, i, value) buf[i] = texelFetch(tex, int(i)) + (value)
#elif defined(EVF_ACCUMULATE)
#define EVF_PUT1(buf, tex, i, value) buf[i] += (value)
#define EVF_PUT3(buf, tex, i, value) buf[i] += (value)
#define EVF_PUT4(buf, tex, i, value) buf[i] += (value)
#else
#define EVF_PUT1(buf, tex, i, value) buf[i] = (value)
#define EVF_PUT3(buf, tex, i, value) buf[i] = (value)
#define EVF_PUT4(buf, tex, i, value) buf[i] = (value)
#endif
// The bands above 0 are added to in place in every build: they are written only at SH degree
// >= 1, which training reaches late (the texel reads cover the buffers written every step).
#ifdef EVF_ACCUMULATE
#define EVF_PUT_BAND(buf, i, value) buf[i] += (value)
#else
#define EVF_PUT_BAND(buf, i, value) buf[i] = (value)
#endif

// SH gradients of bands 0..degree (constant indices after unrolling, see params.glsl). Bands
// above the active degree have zero gradient: the host fills them (Rasterizer::record_backward).
void store_sh_all(uint g, uint degree, vec3 v[16]) {
  EVF_PUT3(v_sh0, VSh0In, g, v[0]);
  if (degree >= 1)
    for (uint k = 0u; k < 3u; ++k) EVF_PUT_BAND(v_sh1, 3u * g + k, v[1u + k]);
  if (degree >= 2)
    for (uint k = 0u; k < 5u; ++k) EVF_PUT_BAND(v_sh2, 5u * g + k, v[4u + k]);
  if (degree >= 3)
    for (uint k = 0u; k < 7u; ++k) EVF_PUT_BAND(v_sh3, 7u * g + k, v[9u + k]);
}

// One Gaussian's parameters, read once for all the renders of a pass.
struct GaussianIn {
  vec3 mean, log_scale;
  vec4 q;
  float logit;
};

GaussianIn load_gaussian(uint g) {
  GaussianIn gi;
  gi.mean = load_mean(g);
  gi.log_scale = load_log_scale(g);
  gi.q = load_quat(g);
  gi.logit = load_opacity_logit(g);
  return gi;
}

// A Gaussian's per-tile gradients of one render, summed in slot order: (v_mean2d, v_conic,
// v_opacity, v_colour). Slots the compositing did not visit, and any emit left unused (sorted
// past every tile), hold the zeros the gradient planes were filled with.
struct SlotSums {
  vec2 v_mean2d;
  vec3 v_conic, v_color;
  float v_opac;
  bool listed;  // in a tile at all (a culled Gaussian gets zeros)
};

SlotSums slot_sums(uint begin, uint end, uint base) {
  SlotSums t;
  t.v_mean2d = vec2(0.0);
  t.v_conic = t.v_color = vec3(0.0);
  t.v_opac = 0.0;
  for (uint s = begin + base; s < end + base; ++s) {
    vec4 ga = slot_grad_a(s), gb = slot_grad_b(s);
    t.v_mean2d += ga.xy;
    t.v_conic += vec3(ga.zw, gb.x);
    t.v_opac += gb.y;
    t.v_color += vec3(gb.zw, slot_grad_c(s));
  }
  t.listed = begin != end;
  return t;
}

// What one render's slot sums give a Gaussian's parameters.
struct RenderGrads {
  vec3 v_mean, v_ls;
  vec4 v_q;
  float v_logit;
  vec3 v_sh[16];
  float pose[6];
};

// The render's chain from the slot sums back to the parameters and the pose (se(3), translation
// first), with `clamped` the forward's max(raw colour, 0) and dcolor(dc .. dc + 2) its d(raw)/d(dir).
// Everything is computed for every Gaussian and selected at the end (a culled one may give
// non-finite intermediates).
RenderGrads render_grads(GaussianIn gi, CameraPC camc, uint flags, uint sh_degree, SlotSums t, vec3 clamped, uint dc) {
  RenderGrads r;
  bool listed = t.listed;
  Camera cam = camera_from(camc);
  vec4 qn = normalize(gi.q);
  vec3 p = cam.R * gi.mean + cam.t;
  mat3 Sigma = covariance_3d(gi.log_scale, qn);
  mat3 Sigma_c = cam.R * Sigma * transpose(cam.R);
  mat3x2 J = ewa_jacobian(p, cam);
  mat2 cov = J * Sigma_c * transpose(J);
  vec3 cov2d = vec3(cov[0][0], cov[0][1], cov[1][1]);
  float sig = 1.0 / (1.0 + exp(-gi.logit));
  bool aa = (flags & kFlagAntialiased) != 0;

  // Colour: rgb = max(sum_k Y_k sh_k + 0.5, 0).
  vec3 campos = camera_center(cam);
  vec3 dvec = gi.mean - campos;
  float dlen = length(dvec);
  vec3 dir = dvec / dlen;
  float Y[16];
  sh_basis(dir, sh_degree, Y);
  vec3 v_raw = listed ? t.v_color * vec3(greaterThan(clamped, vec3(0.0))) : vec3(0.0);
  // Coefficients above the active degree have Y_k = 0: zero gradient, as the contract says.
#define EVF_SH_GRAD(k) r.v_sh[k] = listed ? Y[k] * v_raw : vec3(0.0);
  EVF_SH_GRAD(0) EVF_SH_GRAD(1) EVF_SH_GRAD(2) EVF_SH_GRAD(3) EVF_SH_GRAD(4) EVF_SH_GRAD(5) EVF_SH_GRAD(6)
  EVF_SH_GRAD(7) EVF_SH_GRAD(8) EVF_SH_GRAD(9) EVF_SH_GRAD(10) EVF_SH_GRAD(11) EVF_SH_GRAD(12)
  EVF_SH_GRAD(13) EVF_SH_GRAD(14) EVF_SH_GRAD(15)
  // v_dir = sum_c v_raw_c d(raw_c)/d(dir) (zero at degree 0).
  vec3 v_dir = vec3(0.0);
  if (sh_degree >= 1) v_dir = v_raw.r * dcolor(dc) + v_raw.g * dcolor(dc + 1u) + v_raw.b * dcolor(dc + 2u);
  vec3 v_dvec = (v_dir - dir * dot(dir, v_dir)) / dlen;
  vec3 v_mean = v_dvec;
  vec3 v_campos = -v_dvec;

  // Opacity (and the antialiasing compensation).
  float comp = aa ? aa_compensation(cov2d) : 1.0;
  float v_logit = t.v_opac * comp * sig * (1.0 - sig);
  vec3 v_cov2d = aa ? aa_compensation_vjp(cov2d, t.v_opac * sig) : vec3(0.0);
  // Conic.
  v_cov2d += conic_vjp(cov2d, t.v_conic);
  // cov2d = J Sigma_c J^T.
  mat2 G = mat2(v_cov2d.x, 0.5 * v_cov2d.y, 0.5 * v_cov2d.y, v_cov2d.z);
  mat3x2 v_J = 2.0 * (G * J * Sigma_c);
  mat3 v_Sigma_c = transpose(J) * G * J;
  vec3 v_p = ewa_jacobian_vjp(p, cam, v_J);
  // mean2d = (fx x/z + cx, fy y/z + cy).
  float iz = 1.0 / p.z;
  v_p.x += t.v_mean2d.x * cam.intrin.x * iz;
  v_p.y += t.v_mean2d.y * cam.intrin.y * iz;
  v_p.z -= (t.v_mean2d.x * cam.intrin.x * p.x + t.v_mean2d.y * cam.intrin.y * p.y) * iz * iz;
  // p = R mean + t;  Sigma_c = R Sigma R^T.
  v_mean += transpose(cam.R) * v_p;
  mat3 v_Sigma = transpose(cam.R) * v_Sigma_c * cam.R;
  vec3 v_ls;
  vec4 v_qn;
  covariance_3d_vjp(gi.log_scale, qn, v_Sigma, v_ls, v_qn);
  vec4 v_q = normalize_vjp(gi.q, v_qn);

  // Pose, w2c' = Exp(-delta) w2c: d p = -rho - phi x p, d Sigma_c = -[phi]x Sigma_c + Sigma_c [phi]x,
  // d campos = R^T rho. With N = p v_p^T + 2 Sigma_c v_Sigma_c: dL/dphi = -(N12-N21, N20-N02, N01-N10).
  vec3 v_rho = -v_p + cam.R * v_campos;
  mat3 N = outerProduct(p, v_p) + 2.0 * (Sigma_c * v_Sigma_c);
  r.pose = float[6](0, 0, 0, 0, 0, 0);
  if (listed) {
    r.pose[0] = v_rho.x; r.pose[1] = v_rho.y; r.pose[2] = v_rho.z;
    r.pose[3] = -(N[2][1] - N[1][2]);
    r.pose[4] = -(N[0][2] - N[2][0]);
    r.pose[5] = -(N[1][0] - N[0][1]);
  }
  r.v_mean = listed ? v_mean : vec3(0.0);
  r.v_ls = listed ? v_ls : vec3(0.0);
  r.v_q = listed ? v_q : vec4(0.0);
  r.v_logit = listed ? v_logit : 0.0;
  return r;
}

// The pose partials of `pose` into partial set `set` (a render): one per subgroup, or one per
// workgroup.
void store_pose_partials(float pose[6], uint set, uint sets_stride) {
  uint lid = gl_LocalInvocationIndex;
#ifdef EVF_POSE_PER_SUBGROUP
  // One partial per subgroup ([group][subgroup][6]: the host sizes them by the device's subgroup
  // size), summed with subgroupAdd (a fixed order on a given device) and no barrier: on lavapipe
  // a workgroup barrier suspends every SIMD vector's coroutine, and the barrier and the sum
  // below were about 40 % of this kernel.
  float total[6];
  for (uint k = 0; k < 6; ++k) total[k] = subgroupAdd(pose[k]);
  if (subgroupElect()) {
    // The subgroup's index from the invocation index: subgroups of consecutive invocations, as
    // on lavapipe, where the "_block" builds run. (gl_SubgroupID and gl_NumSubgroups in its place
    // gave wrong pose gradients here on lavapipe, Mesa 22.3, though a probe kernel read them right:
    // not understood, so not relied on.)
    uint per_group = (kProjectGroupSize + gl_SubgroupSize - 1u) / gl_SubgroupSize;
    uint base = (set * sets_stride + evf_linear_group() * per_group + lid / gl_SubgroupSize) * 6u;
    for (uint k = 0; k < 6; ++k) pose_partial[base + k] = total[k];
  }
#else
  // Workgroup reduction of the pose contributions, in a fixed order (deterministic): invocations
  // 0..5 each sum one component over the workgroup. Not a tree: on CPU drivers every step of a
  // tree costs every SIMD vector its masked shared accesses (over half of this kernel's time);
  // this loop has zero trips for all vectors but the first.
  for (uint k = 0; k < 6; ++k) red[k][lid] = pose[k];
  barrier();
  uint len = lid < 6u ? kProjectGroupSize : 0u;
  float sum = 0.0;
  for (uint i = 0; i < len; ++i) sum += red[lid][i];
  if (lid < 6) pose_partial[(set * sets_stride + evf_linear_group()) * 6 + lid] = sum;
#endif
}

#ifndef EVF_FRAMES
void main() {
  uint g = evf_linear_invocation(kProjectGroupSize);
  float pose[6] = float[6](0, 0, 0, 0, 0, 0);
  if (g < pc.num_gaussians) {
    SlotSums t = slot_sums(isect_offset_at(g), isect_offset_at(g + 1u), 0u);
    RenderGrads r = render_grads(load_gaussian(g), pc.cam, pc.flags, pc.sh_degree, t, clamped_color(g), 3u * g);
    pose = r.pose;
    // Only the active bands (at degree 0, 1 of the 16 triples): above it the gradient is zero,
    // which adding leaves as it is and which the host fills in for an overwrite.
    store_sh_all(g, min((pc.flags >> 8) & 3u, pc.sh_degree), r.v_sh);
    EVF_PUT3(v_means, VMeansIn, g, r.v_mean);
    EVF_PUT3(v_log_scales, VLogScalesIn, g, r.v_ls);
    EVF_PUT4(v_quats, VQuatsIn, g, r.v_q);
    EVF_PUT1(v_opacity_logits, VOpacitiesIn, g, r.v_logit);
    EVF_PUT1(grad2d_norm, Grad2dIn, g, length(t.v_mean2d));
  }
  store_pose_partials(pose, 0u, 0u);
}
#else
void main() {
  uint g = evf_linear_invocation(kProjectGroupSize);
  uint n = pc.num_gaussians;
  bool mine = g < n;
  GaussianIn gi = load_gaussian(min(g, n - 1u));
  vec3 v_mean = vec3(0.0), v_ls = vec3(0.0), v_sh[16];
  vec4 v_q = vec4(0.0);
  float v_logit = 0.0, g2d = 0.0;
  for (uint k = 0u; k < 16u; ++k) v_sh[k] = vec3(0.0);
  for (uint f = 0u; f < pc.frames; ++f) {
    float pose[6] = float[6](0, 0, 0, 0, 0, 0);
    if (mine) {
      uint o = f * (n + 1u) + g;
      SlotSums t = slot_sums(isect_offset_at(o), isect_offset_at(o + 1u), pc.slot_base[f]);
      RenderGrads r = render_grads(gi, frame_camera(f), pc.flags, pc.sh_degree, t, clamped_color(f * n + g),
                                   3u * (f * n + g));
      pose = r.pose;
      // In the order of one pass per frame: the first overwrites (0 + x = x), the others add.
      v_mean += r.v_mean;
      v_ls += r.v_ls;
      v_q += r.v_q;
      v_logit += r.v_logit;
      g2d += length(t.v_mean2d);
      for (uint k = 0u; k < 16u; ++k) v_sh[k] += r.v_sh[k];
    }
    store_pose_partials(pose, f, pc.partials);
  }
  if (mine) {
    store_sh_all(g, min((pc.flags >> 8) & 3u, pc.sh_degree), v_sh);
    v_means[g] = v_mean;
    v_log_scales[g] = v_ls;
    v_quats[g] = v_q;
    v_opacity_logits[g] = v_logit;
    grad2d_norm[g] = g2d;
  }
}
#endif
