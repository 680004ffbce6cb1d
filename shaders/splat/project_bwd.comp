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
layout(push_constant) uniform PC { ProjectPC pc; };

#ifdef EVF_POSE_PER_SUBGROUP
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#else
shared float red[6][kProjectGroupSize];
#endif

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

void main() {
  uint g = evf_linear_invocation(kProjectGroupSize);
  uint lid = gl_LocalInvocationIndex;
  float pose[6] = float[6](0, 0, 0, 0, 0, 0);
  if (g < pc.num_gaussians) {
    uint buffer_degree = (pc.flags >> 8) & 3u;
    // Sum of this Gaussian's per-tile gradients, in slot order.
    vec2 v_mean2d = vec2(0.0);
    vec3 v_conic = vec3(0.0), v_color = vec3(0.0);
    float v_opac = 0.0;
    uint begin = isect_offset_at(g), end = isect_offset_at(g + 1u);
    // Slots the compositing did not visit, and any emit left unused (sorted past every tile),
    // hold the zeros the gradient planes were filled with.
    for (uint s = begin; s < end; ++s) {
      vec4 ga = slot_grad_a(s), gb = slot_grad_b(s);
      v_mean2d += ga.xy;
      v_conic += vec3(ga.zw, gb.x);
      v_opac += gb.y;
      v_color += vec3(gb.zw, slot_grad_c(s));
    }
    // A Gaussian in no tile (culled) gets zeros. Everything below is computed for every
    // Gaussian and selected at the end (a culled one may give non-finite intermediates).
    bool listed = begin != end;

    // Recompute the forward intermediates.
    Camera cam = camera_from(pc.cam);
    vec3 mean = load_mean(g), log_scale = load_log_scale(g);
    vec4 q = load_quat(g);
    vec4 qn = normalize(q);
    vec3 p = cam.R * mean + cam.t;
    mat3 Sigma = covariance_3d(log_scale, qn);
    mat3 Sigma_c = cam.R * Sigma * transpose(cam.R);
    mat3x2 J = ewa_jacobian(p, cam);
    mat2 cov = J * Sigma_c * transpose(J);
    vec3 cov2d = vec3(cov[0][0], cov[0][1], cov[1][1]);
    float sig = 1.0 / (1.0 + exp(-load_opacity_logit(g)));
    bool aa = (pc.flags & kFlagAntialiased) != 0;

    // Colour: rgb = max(sum_k Y_k sh_k + 0.5, 0).
    vec3 campos = camera_center(cam);
    vec3 dvec = mean - campos;
    float dlen = length(dvec);
    vec3 dir = dvec / dlen;
    float Y[16];
    sh_basis(dir, pc.sh_degree, Y);
    vec3 clamped = clamped_color(g);
    vec3 v_raw = listed ? v_color * vec3(greaterThan(clamped, vec3(0.0))) : vec3(0.0);
    // Coefficients above the active degree have Y_k = 0: zero gradient, as the contract says.
    vec3 v_sh[16];
#define EVF_SH_GRAD(k) v_sh[k] = listed ? Y[k] * v_raw : vec3(0.0);
    EVF_SH_GRAD(0) EVF_SH_GRAD(1) EVF_SH_GRAD(2) EVF_SH_GRAD(3) EVF_SH_GRAD(4) EVF_SH_GRAD(5) EVF_SH_GRAD(6)
    EVF_SH_GRAD(7) EVF_SH_GRAD(8) EVF_SH_GRAD(9) EVF_SH_GRAD(10) EVF_SH_GRAD(11) EVF_SH_GRAD(12)
    EVF_SH_GRAD(13) EVF_SH_GRAD(14) EVF_SH_GRAD(15)
    // Only the active bands (at degree 0, 1 of the 16 triples): above it the gradient is zero,
    // which adding leaves as it is and which the host fills in for an overwrite.
    store_sh_all(g, min(buffer_degree, pc.sh_degree), v_sh);
    // v_dir = sum_c v_raw_c d(raw_c)/d(dir) (zero at degree 0).
    vec3 v_dir = vec3(0.0);
    if (pc.sh_degree >= 1) {
      uint i = 3 * g;
      v_dir = v_raw.r * dcolor(i) + v_raw.g * dcolor(i + 1u) + v_raw.b * dcolor(i + 2u);
    }
    vec3 v_dvec = (v_dir - dir * dot(dir, v_dir)) / dlen;
    vec3 v_mean = v_dvec;
    vec3 v_campos = -v_dvec;

    // Opacity (and the antialiasing compensation).
    float comp = aa ? aa_compensation(cov2d) : 1.0;
    float v_logit = v_opac * comp * sig * (1.0 - sig);
    vec3 v_cov2d = aa ? aa_compensation_vjp(cov2d, v_opac * sig) : vec3(0.0);
    // Conic.
    v_cov2d += conic_vjp(cov2d, v_conic);
    // cov2d = J Sigma_c J^T.
    mat2 G = mat2(v_cov2d.x, 0.5 * v_cov2d.y, 0.5 * v_cov2d.y, v_cov2d.z);
    mat3x2 v_J = 2.0 * (G * J * Sigma_c);
    mat3 v_Sigma_c = transpose(J) * G * J;
    vec3 v_p = ewa_jacobian_vjp(p, cam, v_J);
    // mean2d = (fx x/z + cx, fy y/z + cy).
    float iz = 1.0 / p.z;
    v_p.x += v_mean2d.x * cam.intrin.x * iz;
    v_p.y += v_mean2d.y * cam.intrin.y * iz;
    v_p.z -= (v_mean2d.x * cam.intrin.x * p.x + v_mean2d.y * cam.intrin.y * p.y) * iz * iz;
    // p = R mean + t;  Sigma_c = R Sigma R^T.
    v_mean += transpose(cam.R) * v_p;
    mat3 v_Sigma = transpose(cam.R) * v_Sigma_c * cam.R;
    vec3 v_ls;
    vec4 v_qn;
    covariance_3d_vjp(log_scale, qn, v_Sigma, v_ls, v_qn);
    vec4 v_q = normalize_vjp(q, v_qn);

    // Pose, w2c' = Exp(-delta) w2c: d p = -rho - phi x p, d Sigma_c = -[phi]x Sigma_c + Sigma_c [phi]x,
    // d campos = R^T rho. With N = p v_p^T + 2 Sigma_c v_Sigma_c: dL/dphi = -(N12-N21, N20-N02, N01-N10).
    vec3 v_rho = -v_p + cam.R * v_campos;
    mat3 N = outerProduct(p, v_p) + 2.0 * (Sigma_c * v_Sigma_c);
    if (listed) {
      pose[0] = v_rho.x; pose[1] = v_rho.y; pose[2] = v_rho.z;
      pose[3] = -(N[2][1] - N[1][2]);
      pose[4] = -(N[0][2] - N[2][0]);
      pose[5] = -(N[1][0] - N[0][1]);
    }
    v_mean = listed ? v_mean : vec3(0.0);
    v_ls = listed ? v_ls : vec3(0.0);
    v_q = listed ? v_q : vec4(0.0);
    v_logit = listed ? v_logit : 0.0;
    EVF_PUT3(v_means, VMeansIn, g, v_mean);
    EVF_PUT3(v_log_scales, VLogScalesIn, g, v_ls);
    EVF_PUT4(v_quats, VQuatsIn, g, v_q);
    EVF_PUT1(v_opacity_logits, VOpacitiesIn, g, v_logit);
    EVF_PUT1(grad2d_norm, Grad2dIn, g, length(v_mean2d));
  }
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
    uint base = (evf_linear_group() * per_group + lid / gl_SubgroupSize) * 6u;
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
  if (lid < 6) pose_partial[evf_linear_group() * 6 + lid] = sum;
#endif
}
