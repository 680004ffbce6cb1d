#version 450
// Per pixel: the visible triangle's perspective-correct UVs (at 1 or 4 sub-pixel rays, for
// texture anti-aliasing), trilinear (mip-mapped) base-colour texture (sRGB RGBA8 texels decoded to linear),
// base colour factor, ambient + Lambert lighting with the face normal turned towards the camera.
// Output: linear RGB and camera depth z (0 where nothing is hit: background colour).
#extension GL_GOOGLE_include_directive : require
#include "sim/sim_layout.h"
#include "common/dispatch.glsl"
#include "sim/raster_common.glsl"
layout(local_size_x = kSimShadeGroupSize) in;
layout(std430, binding = kSimShadeBindTris) readonly buffer Tris { SimTriangle tris[]; };
layout(std430, binding = kSimShadeBindCamVerts) readonly buffer CamVerts { vec4 cam[]; };
layout(std430, binding = kSimShadeBindIds) readonly buffer Ids { uint ids[]; };
layout(std430, binding = kSimShadeBindMaterials) readonly buffer Materials { SimMaterial materials[]; };
layout(std430, binding = kSimShadeBindTexels) readonly buffer Texels { uint texels[]; };
layout(std430, binding = kSimShadeBindOut) writeonly buffer Out { vec4 image[]; };
layout(push_constant) uniform PC { SimPC pc; };

float srgb_decode(float c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }
vec4 texel(uint base, uint w, uint x, uint y) {
  vec4 c = unpackUnorm4x8(texels[base + y * w + x]);
  return vec4(srgb_decode(c.r), srgb_decode(c.g), srgb_decode(c.b), c.a);
}
int wrap(int i, int n, uint mode) {
  if (mode == 1u) return clamp(i, 0, n - 1);
  if (mode == 2u) {
    int m = i % (2 * n); if (m < 0) m += 2 * n;
    return m < n ? m : 2 * n - 1 - m;
  }
  int m = i % n; return m < 0 ? m + n : m;
}
vec4 sample_level(SimMaterial m, vec2 uv, uint level) {
  uint b = m.tex.x;
  int w = int(m.tex.y), h = int(m.tex.z);
  for (uint l = 0u; l < level; ++l) {
    b += uint(w * h);
    w = max(1, w >> 1);
    h = max(1, h >> 1);
  }
  vec2 f = uv * vec2(w, h) - 0.5;
  vec2 fl = floor(f);
  vec2 a = f - fl;
  int x0 = int(fl.x), y0 = int(fl.y);
  uint ms = m.tex.w & 3u, mt = (m.tex.w >> 2) & 3u;
  uint xa = uint(wrap(x0, w, ms)), xb = uint(wrap(x0 + 1, w, ms));
  uint ya = uint(wrap(y0, h, mt)), yb = uint(wrap(y0 + 1, h, mt));
  uint uw = uint(w);
  return mix(mix(texel(b, uw, xa, ya), texel(b, uw, xb, ya), a.x), mix(texel(b, uw, xa, yb), texel(b, uw, xb, yb), a.x), a.y);
}
// Trilinear lookup; footprint: the UV change across one sample's footprint in x and in y.
vec4 sample_tex(SimMaterial m, vec2 uv, vec2 duv_x, vec2 duv_y) {
  if (m.tex.x == kSimNoTexture) return vec4(1.0);
  // Keep the coordinates small so float keeps sub-texel precision (period 1 repeat, 2 mirror).
  uint ms = m.tex.w & 3u, mt = (m.tex.w >> 2) & 3u;
  if (ms == 0u) uv.x -= floor(uv.x); else if (ms == 2u) uv.x -= 2.0 * floor(0.5 * uv.x);
  if (mt == 0u) uv.y -= floor(uv.y); else if (mt == 2u) uv.y -= 2.0 * floor(0.5 * uv.y);
  vec2 size = vec2(m.tex.y, m.tex.z);
  float f = max(length(duv_x * size), length(duv_y * size));
  uint levels = (m.tex.w >> 8) & 255u;
  float lod = clamp(log2(max(f, 1e-8)), 0.0, float(levels - 1u));
  if (lod < 1e-3) return sample_level(m, uv, 0u);
  uint l0 = uint(floor(lod));
  float t = lod - float(l0);
  vec4 c0 = sample_level(m, uv, l0);
  return t > 0.0 ? mix(c0, sample_level(m, uv, min(l0 + 1u, levels - 1u)), t) : c0;
}

void main() {
  uint p = evf_linear_invocation(64u);
  uint W = pc.dims.x;
  if (p >= W * pc.dims.y) return;
  uint tri = ids[p];
  if (tri == kSimNoTriangle) { image[p] = vec4(pc.background.rgb, 0.0); return; }
  vec2 pix = vec2(p % W, p / W) + 0.5;
  vec3 v0 = cam[3u * tri].xyz, v1 = cam[3u * tri + 1u].xyz, v2 = cam[3u * tri + 2u].xyz;
  SimTriangle T = tris[tri];
  SimMaterial m = materials[uint(T.p0.w)];
  vec3 lc = sim_plane_lambda(sim_ray(pc, pix), v0, v1, v2);
  float z = lc.x * v0.z + lc.y * v1.z + lc.z * v2.z;
  // UV derivatives per pixel from the plane barycentrics one pixel to the right and below.
  vec3 lx = sim_plane_lambda(sim_ray(pc, pix + vec2(1.0, 0.0)), v0, v1, v2);
  vec3 ly = sim_plane_lambda(sim_ray(pc, pix + vec2(0.0, 1.0)), v0, v1, v2);
  vec2 uvc = lc.x * T.uv01.xy + lc.y * T.uv01.zw + lc.z * T.uv2.xy;
  vec2 dx = lx.x * T.uv01.xy + lx.y * T.uv01.zw + lx.z * T.uv2.xy - uvc;
  vec2 dy = ly.x * T.uv01.xy + ly.y * T.uv01.zw + ly.z * T.uv2.xy - uvc;
  vec4 albedo = vec4(0.0);
  if (pc.misc.y > 1.5) {
    for (uint k = 0u; k < 4u; ++k) {
      vec2 o = vec2((k & 1u) == 0u ? -0.25 : 0.25, (k & 2u) == 0u ? -0.25 : 0.25);
      vec3 l = sim_plane_lambda(sim_ray(pc, pix + o), v0, v1, v2);
      vec2 uv = l.x * T.uv01.xy + l.y * T.uv01.zw + l.z * T.uv2.xy;
      albedo += 0.25 * sample_tex(m, uv, 0.5 * dx, 0.5 * dy);
    }
  } else {
    albedo = sample_tex(m, uvc, dx, dy);
  }
  albedo *= m.factor;
  // Face normal in the camera frame, turned towards the camera, then to world (n_w = R^T n_c).
  vec3 nc = cross(v1 - v0, v2 - v0);
  if (dot(nc, v0) > 0.0) nc = -nc;
  float len = length(nc);
  nc = len > 0.0 ? nc / len : vec3(0.0, 0.0, -1.0);
  vec3 nw = nc.x * pc.r0.xyz + nc.y * pc.r1.xyz + nc.z * pc.r2.xyz;
  float lambert = max(dot(nw, pc.light.xyz), 0.0);
  float shade = pc.light.w + (1.0 - pc.light.w) * lambert;
  image[p] = vec4(albedo.rgb * shade, z);
}
