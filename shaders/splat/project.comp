#version 450
// Projection: one invocation per Gaussian. Computes its screen-space mean, conic, effective
// opacity, colour from SH and camera depth, and counts the 16x16 tiles its support ellipse
// meets (0 when culled).
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_scalar_block_layout : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
layout(local_size_x = kProjectGroupSize) in;
#include "splat/params.glsl"
layout(std430, binding = kProjectBindProjA) writeonly buffer ProjA { vec4 proj_mean_conic[]; };  // mean.xy, conic.xy
layout(std430, binding = kProjectBindProjB) writeonly buffer ProjB { vec4 proj_misc[]; };        // conic.z, opacity, depth, q_max
layout(std430, binding = kProjectBindProjC) writeonly buffer ProjC { vec4 proj_color[]; };       // rgb, 0
layout(std430, binding = kProjectBindRect) writeonly buffer Rect { uvec4 tile_rect[]; };         // tile_rect_pack
layout(std430, binding = kProjectBindCount) writeonly buffer Count { uint tiles_touched[]; };
// d(raw colour channel c)/d(view direction), [N][3 channels][3], for project_bwd (SH degree >= 1;
// a placeholder buffer at degree 0, never written). project_bwd then needs no SH coefficients.
layout(std430, binding = kProjectBindDColor) writeonly buffer DColor { vec4 proj_dcolor[]; };  // [N][3] (.xyz)
layout(push_constant) uniform PC { ProjectPC pc; };

// Culling selects zeros at the end instead of returning early: on CPU drivers (lavapipe) an
// early return is a lane mask, and each of several culling exits would run its own stores.
void main() {
  uint g = evf_linear_invocation(kProjectGroupSize);
  if (g >= pc.num_gaussians) return;
  Camera cam = camera_from(pc.cam);
  vec3 mean = load_mean(g);
  vec3 p = cam.R * mean + cam.t;
  bool keep = p.z >= pc.cam.near_plane && p.z <= pc.cam.far_plane;
  vec4 qn = normalize(load_quat(g));
  mat3 Sigma_c = cam.R * covariance_3d(load_log_scale(g), qn) * transpose(cam.R);
  mat3x2 J = ewa_jacobian(p, cam);
  mat2 cov = J * Sigma_c * transpose(J);
  vec3 cov2d = vec3(cov[0][0], cov[0][1], cov[1][1]);
  float detd = (cov2d.x + kDilation) * (cov2d.z + kDilation) - cov2d.y * cov2d.y;
  keep = keep && detd > 0.0;
  vec3 conic = conic_of(cov2d);
  float opacity = 1.0 / (1.0 + exp(-load_opacity_logit(g)));
  if ((pc.flags & kFlagAntialiased) != 0) opacity *= aa_compensation(cov2d);
  keep = keep && opacity >= kAlphaMin;
  float q_max = 2.0 * log(255.0 * opacity);
  vec2 mean2d = vec2(cam.intrin.x * p.x / p.z + cam.intrin.z, cam.intrin.y * p.y / p.z + cam.intrin.w);
  vec2 ext = support_extent(cov2d, q_max);
  // Pixels whose centre (x + 0.5) lies in [mean - ext, mean + ext].
  vec2 lo_px = max(ceil(mean2d - ext - 0.5), vec2(0.0));
  vec2 hi_px = min(floor(mean2d + ext - 0.5), cam.size - 1.0);
  keep = keep && !any(greaterThan(lo_px, hi_px));
  // (Values of culled Gaussians may be non-finite: nothing below uses them unselected.)
  uvec2 t0 = keep ? uvec2(lo_px) / kTileSize : uvec2(0), t1 = keep ? uvec2(hi_px) / kTileSize + 1u : uvec2(0);
  uint count = 0, mask = 0u, k = 0u;  // k: the tile's index in the rectangle, row by row
  for (uint ty = t0.y; ty < t1.y; ++ty)
    for (uint tx = t0.x; tx < t1.x; ++tx, ++k) {
      vec2 lo = vec2(tx * kTileSize, ty * kTileSize) + 0.5, hi = lo + float(kTileSize - 1);
      if (ellipse_meets_rect(mean2d, conic, q_max, lo, hi)) {
        count++;
        mask |= (1u << (k & 31u)) * uint(k < kTileMaskTiles);
      }
    }
  // Colour from SH along the viewing direction.
  vec3 dir = normalize(mean - camera_center(cam));
  float Y[16];
  sh_basis(dir, pc.sh_degree, Y);
  // Only the active bands: above the active degree Y is zero, and so is what they would add.
  vec3 coeffs[16];
  load_sh_all(g, min((pc.flags >> 8) & 3u, pc.sh_degree), coeffs);
  vec3 rgb = sh_eval(vec3(0.5), Y, coeffs);
  if (pc.sh_degree >= 1) {
    float wr[16], wg[16], wb[16];
#define EVF_SPLIT(k) wr[k] = coeffs[k].r; wg[k] = coeffs[k].g; wb[k] = coeffs[k].b;
    EVF_SPLIT(0) EVF_SPLIT(1) EVF_SPLIT(2) EVF_SPLIT(3) EVF_SPLIT(4) EVF_SPLIT(5) EVF_SPLIT(6) EVF_SPLIT(7)
    EVF_SPLIT(8) EVF_SPLIT(9) EVF_SPLIT(10) EVF_SPLIT(11) EVF_SPLIT(12) EVF_SPLIT(13) EVF_SPLIT(14) EVF_SPLIT(15)
    vec3 jr = sh_basis_vjp(dir, pc.sh_degree, wr), jg = sh_basis_vjp(dir, pc.sh_degree, wg),
         jb = sh_basis_vjp(dir, pc.sh_degree, wb);
    proj_dcolor[3 * g] = vec4(jr, 0.0);
    proj_dcolor[3 * g + 1] = vec4(jg, 0.0);
    proj_dcolor[3 * g + 2] = vec4(jb, 0.0);
  }
  tiles_touched[g] = count;  // 0 when culled
  tile_rect[g] = tile_rect_pack(t0, t1, mask);
  proj_mean_conic[g] = keep ? vec4(mean2d, conic.xy) : vec4(0.0);
  proj_misc[g] = keep ? vec4(conic.z, opacity, p.z, q_max) : vec4(0.0);
  proj_color[g] = keep ? vec4(max(rgb, vec3(0.0)), 0.0) : vec4(0.0);
}
