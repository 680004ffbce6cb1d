#version 450
// Backward rasterization: one workgroup per 16x16 tile, one invocation per pixel, walking the
// tile's Gaussians back to front from each pixel's final transmittance and last blended index.
// Per Gaussian, the 256 pixels' gradients are summed inside the workgroup (subgroupAdd, then
// one shared-memory add per subgroup) and written once to the Gaussian's intersection slot:
// no global atomics, so project_bwd sums each Gaussian's slots in a fixed order.
// EVF_CAS_ATOMICS builds the variant for devices without shared float atomics.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#ifndef EVF_CAS_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
layout(local_size_x = kTileSize, local_size_y = kTileSize) in;
#include "splat/raster_io.glsl"
layout(std430, binding = kRasterizeBwdBindInT) readonly buffer InT { float final_T[]; };
layout(std430, binding = kRasterizeBwdBindInLast) readonly buffer InLast { uint last_isect[]; };
layout(std430, binding = kRasterizeBwdBindVRgb) readonly buffer VRgb { float v_rgb[]; };        // [3][H][W]
layout(std430, binding = kRasterizeBwdBindVAlpha) readonly buffer VAlpha { float v_alpha[]; };  // [H][W]
// Per-slot gradients (splat_layout.h): (v_mean2d.xy, v_conic.xy), (v_conic.z, v_opacity, v_rgb.rg), v_rgb.b.
layout(std430, binding = kRasterizeBwdBindG0) writeonly buffer G0 { vec4 slot_grad_a[]; };
layout(std430, binding = kRasterizeBwdBindG1) writeonly buffer G1 { vec4 slot_grad_b[]; };
layout(std430, binding = kRasterizeBwdBindG2) writeonly buffer G2 { float slot_grad_c[]; };
layout(push_constant) uniform PC { RasterPC pc; };
shared uint tile_last;

#ifdef EVF_CAS_ATOMICS
shared uint acc[256 * 9];
void acc_add(uint i, float v) {
  uint old = acc[i];
  for (;;) {
    uint prev = atomicCompSwap(acc[i], old, floatBitsToUint(uintBitsToFloat(old) + v));
    if (prev == old) break;
    old = prev;
  }
}
float acc_get(uint i) { return uintBitsToFloat(acc[i]); }
void acc_zero(uint i) { acc[i] = 0u; }
#else
shared float acc[256 * 9];
void acc_add(uint i, float v) { atomicAdd(acc[i], v); }
float acc_get(uint i) { return acc[i]; }
void acc_zero(uint i) { acc[i] = 0.0; }
#endif

void main() {
  ivec2 tile = tile_of_group(pc.tiles_x);
  ivec2 pix = tile * int(kTileSize) + ivec2(gl_LocalInvocationID.xy);
  bool inside = pix.x < int(pc.width) && pix.y < int(pc.height);
  vec2 centre = vec2(pix) + 0.5;
  uvec2 range = tile_range[tile.y * pc.tiles_x + tile.x];
  uint hw = pc.width * pc.height, pi = inside ? uint(pix.y) * pc.width + uint(pix.x) : 0u;
  float T = inside ? final_T[pi] : 1.0;
  float T_final = T;
  uint last = inside ? last_isect[pi] : range.x;
  vec3 v_C = inside ? vec3(v_rgb[pi], v_rgb[hw + pi], v_rgb[2 * hw + pi]) : vec3(0.0);
  float v_A = inside ? v_alpha[pi] : 0.0;
  vec3 S = pc.background.rgb * T_final;  // colour of everything behind the current Gaussian
  uint lid = gl_LocalInvocationIndex;
  uint count = range.y - range.x;
  // Gaussians at or past the tile's largest `last` blended into no pixel: neither loaded nor
  // visited, their slots keep the zeros the host filled the gradient planes with.
  if (lid == 0) tile_last = range.x;
  barrier();
  atomicMax(tile_last, last);
  barrier();
  uint visit_end = tile_last;
  for (uint nb = (count + 255u) / 256u; nb > 0u; --nb) {
    uint start = range.x + (nb - 1u) * 256u;
    uint n = min(256u, range.y - start);
    barrier();
    uint n_load = start < visit_end ? min(n, visit_end - start) : 0u;
    if (lid < n_load) load_batch_entry(lid, start + lid);
    for (uint k = 0; k < 9; ++k) acc_zero(lid * 9 + k);
    barrier();
    uint n_visit = n_load;
    // Per-lane adds need no uniform control flow, so each pixel starts at its own last Gaussian
    // (CPU drivers then run a SIMD vector only as far as its furthest pixel); the subgroup
    // reduction needs every lane at the same j.
    if (pc.subgroup_reduce == 0u) n_visit = (inside && start < last) ? min(n, last - start) : 0u;
    for (uint jj = n_visit; jj > 0u; --jj) {
      uint j = jj - 1u;
      bool contrib = inside && start + j < last;
      // Plain scalars, no arrays: CPU drivers spill dynamically indexed private arrays.
      vec2 g_mean = vec2(0.0);
      vec3 g_conic = vec3(0.0), g_rgb = vec3(0.0);
      float g_opac = 0.0;
      if (contrib) {
        vec4 a = batch_mean_conic[j], b = batch_misc[j];
        vec3 conic = vec3(a.zw, b.x);
        vec2 d = a.xy - centre;
        float power = splat_power(conic, d);
        float G = exp(power);
        float raw = b.y * G;
        float alpha = min(kAlphaMax, raw);
        if (alpha < kAlphaMin) {
          contrib = false;
        } else {
          vec3 col = batch_color[j];
          float one_minus = 1.0 - alpha;
          float T_before = T / one_minus;
          g_rgb = (alpha * T_before) * v_C;
          float v_alpha_j = T_before * dot(col, v_C) - dot(S, v_C) / one_minus + v_A * T_final / one_minus;
          S += col * (alpha * T_before);
          T = T_before;
          if (raw < kAlphaMax) {
            float v_power = alpha * v_alpha_j;
            g_mean = -v_power * vec2(conic.x * d.x + conic.y * d.y, conic.y * d.x + conic.z * d.y);
            g_conic = v_power * vec3(-0.5 * d.x * d.x, -d.x * d.y, -0.5 * d.y * d.y);
            g_opac = G * v_alpha_j;
          }
        }
      }
      uint o = j * 9u;
      if (pc.subgroup_reduce != 0u) {
        // GPUs: sum over the subgroup first, one shared add per subgroup.
        if (subgroupAny(contrib)) {
          g_mean = subgroupAdd(g_mean);
          g_conic = subgroupAdd(g_conic);
          g_opac = subgroupAdd(g_opac);
          g_rgb = subgroupAdd(g_rgb);
          if (subgroupElect()) {
            acc_add(o, g_mean.x); acc_add(o + 1, g_mean.y);
            acc_add(o + 2, g_conic.x); acc_add(o + 3, g_conic.y); acc_add(o + 4, g_conic.z);
            acc_add(o + 5, g_opac);
            acc_add(o + 6, g_rgb.r); acc_add(o + 7, g_rgb.g); acc_add(o + 8, g_rgb.b);
          }
        }
      } else if (contrib) {
        // CPU drivers (lavapipe): cross-lane operations cost more than per-lane shared adds.
        acc_add(o, g_mean.x); acc_add(o + 1, g_mean.y);
        acc_add(o + 2, g_conic.x); acc_add(o + 3, g_conic.y); acc_add(o + 4, g_conic.z);
        acc_add(o + 5, g_opac);
        acc_add(o + 6, g_rgb.r); acc_add(o + 7, g_rgb.g); acc_add(o + 8, g_rgb.b);
      }
    }
    barrier();
    if (lid < n_load) {
      uint slot = batch_slot[lid], o = lid * 9;
      slot_grad_a[slot] = vec4(acc_get(o), acc_get(o + 1), acc_get(o + 2), acc_get(o + 3));
      slot_grad_b[slot] = vec4(acc_get(o + 4), acc_get(o + 5), acc_get(o + 6), acc_get(o + 7));
      slot_grad_c[slot] = acc_get(o + 8);
    }
  }
}
