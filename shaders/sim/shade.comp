#version 450
// Per pixel: the visible triangle's perspective-correct UVs (at 1 or 4 sub-pixel rays, for
// texture anti-aliasing), trilinear (mip-mapped) base-colour texture (sRGB RGBA8 texels decoded to
// linear through a table of the 256 codes: a texel fetch where a pow would be, 96 of them a pixel
// at 4 rays; the texels and the table are read as texel buffers, on CPU drivers straight-line code
// where a storage load is a loop over the lanes), base colour factor, ambient + Lambert lighting
// with the face normal turned towards the camera. The texture's alpha is not used.
// Output: linear RGB and camera depth z (0 where nothing is hit: background colour).
#extension GL_GOOGLE_include_directive : require
#include "sim/sim_layout.h"
#include "common/dispatch.glsl"
#include "sim/raster_common.glsl"
layout(local_size_x = kSimShadeGroupSize) in;
layout(binding = kSimShadeBindTris) uniform samplerBuffer Tris;               // SimTriangle: 5 texels
layout(binding = kSimShadeBindCamVerts) uniform samplerBuffer CamVerts;       // 3 texels a triangle
layout(binding = kSimShadeBindIds) uniform usamplerBuffer Ids;
layout(binding = kSimShadeBindMaterials) uniform usamplerBuffer Materials;  // SimMaterial: 8 words
layout(binding = kSimShadeBindTexels) uniform usamplerBuffer Texels;
layout(binding = kSimShadeBindDecode) uniform samplerBuffer Decode;
layout(std430, binding = kSimShadeBindOut) writeonly buffer Out { vec4 image[]; };
layout(push_constant) uniform PC { SimPC pc; };

SimMaterial material(uint i) {
  uint b = 8u * i;
  SimMaterial m;
  for (uint k = 0u; k < 4u; ++k) {
    m.factor[k] = uintBitsToFloat(texelFetch(Materials, int(b + k)).x);
    m.tex[k] = texelFetch(Materials, int(b + 4u + k)).x;
  }
  return m;
}
float decode(uint code) { return texelFetch(Decode, int(code >> 2u))[code & 3u]; }
vec3 texel(uint base, uint w, uint x, uint y) {
  uint c = texelFetch(Texels, int(base + y * w + x)).x;
  return vec3(decode(c & 255u), decode((c >> 8u) & 255u), decode((c >> 16u) & 255u));
}
// i mod n in [0, n) for |i| < 2^24, through a float quotient: CPUs have no vector integer
// division, so CPU drivers run an integer % lane by lane.
int floor_mod(int i, int n) {
  int m = i - n * int(floor(float(i) / float(n)));
  return m < 0 ? m + n : (m >= n ? m - n : m);
}
int wrap(int i, int n, uint mode) {
  if (mode == 1u) return clamp(i, 0, n - 1);
  if (mode == 2u) {
    int m = floor_mod(i, 2 * n);
    return m < n ? m : 2 * n - 1 - m;
  }
  return floor_mod(i, n);
}
// One mip level of a texture: its first texel and size (level l: max(1, w >> l) x max(1, h >> l)).
struct Level {
  uint base;
  int w, h;
};
Level level_of(SimMaterial m, uint level) {
  Level L = Level(m.tex.x, int(m.tex.y), int(m.tex.z));
  for (uint l = 0u; l < level; ++l) {
    L.base += uint(L.w * L.h);
    L.w = max(1, L.w >> 1);
    L.h = max(1, L.h >> 1);
  }
  return L;
}
vec3 bilinear(Level L, uint ms, uint mt, vec2 uv) {
  vec2 f = uv * vec2(L.w, L.h) - 0.5;
  vec2 fl = floor(f);
  vec2 a = f - fl;
  int x0 = int(fl.x), y0 = int(fl.y);
  uint xa = uint(wrap(x0, L.w, ms)), xb = uint(wrap(x0 + 1, L.w, ms));
  uint ya = uint(wrap(y0, L.h, mt)), yb = uint(wrap(y0 + 1, L.h, mt));
  uint uw = uint(L.w);
  return mix(mix(texel(L.base, uw, xa, ya), texel(L.base, uw, xb, ya), a.x),
             mix(texel(L.base, uw, xa, yb), texel(L.base, uw, xb, yb), a.x), a.y);
}
// A pixel's trilinear lookups share one footprint (the UV change across one sample in x and in
// y), so its levels and their blend are found once for all of its rays.
struct Lookup {
  Level l0, l1;
  float t;  // l1's share; 0: l0 alone
  uint ms, mt;
};
Lookup lookup_of(SimMaterial m, vec2 duv_x, vec2 duv_y) {
  vec2 size = vec2(m.tex.y, m.tex.z);
  float f = max(length(duv_x * size), length(duv_y * size));
  uint levels = (m.tex.w >> 8) & 255u;
  float lod = clamp(log2(max(f, 1e-8)), 0.0, float(levels - 1u));
  uint l0 = lod < 1e-3 ? 0u : uint(floor(lod));
  Lookup k;
  k.t = lod < 1e-3 ? 0.0 : lod - float(l0);
  k.l0 = level_of(m, l0);
  k.l1 = level_of(m, min(l0 + 1u, levels - 1u));
  k.ms = m.tex.w & 3u;
  k.mt = (m.tex.w >> 2) & 3u;
  return k;
}
vec3 sample_tex(Lookup k, vec2 uv) {
  // Keep the coordinates small so float keeps sub-texel precision (period 1 repeat, 2 mirror).
  if (k.ms == 0u) uv.x -= floor(uv.x); else if (k.ms == 2u) uv.x -= 2.0 * floor(0.5 * uv.x);
  if (k.mt == 0u) uv.y -= floor(uv.y); else if (k.mt == 2u) uv.y -= 2.0 * floor(0.5 * uv.y);
  vec3 c0 = bilinear(k.l0, k.ms, k.mt, uv);
  return k.t > 0.0 ? mix(c0, bilinear(k.l1, k.ms, k.mt, uv), k.t) : c0;
}
// Barycentrics of the ray through pixel point `pix` on the triangle's plane (not clipped to the
// triangle: the neighbours' UVs give the footprint); c: the vertices' crosses, once a pixel.
vec3 lambda_at(vec2 pix, mat3 c) {
  vec3 e = sim_ray(pc, pix) * c;
  float s = e.x + e.y + e.z;
  return s != 0.0 ? e / s : vec3(1.0 / 3.0);
}

void main() {
  uint p = evf_linear_invocation(kSimShadeGroupSize);
  uint W = pc.dims.x;
  if (p >= W * pc.dims.y) return;
  uint tri = texelFetch(Ids, int(p)).x;
  if (tri == kSimNoTriangle) { image[p] = vec4(pc.background.rgb, 0.0); return; }
  vec2 pix = vec2(p % W, p / W) + 0.5;
  int c3 = int(3u * tri), t5 = int(5u * tri);
  vec3 v0 = texelFetch(CamVerts, c3).xyz, v1 = texelFetch(CamVerts, c3 + 1).xyz, v2 = texelFetch(CamVerts, c3 + 2).xyz;
  // Of the SimTriangle, shading reads p0.w (the material), uv01 and uv2.
  SimMaterial m = material(uint(texelFetch(Tris, t5).w));
  vec4 uv01 = texelFetch(Tris, t5 + 3);
  vec2 uv2 = texelFetch(Tris, t5 + 4).xy;
  const mat3 c = mat3(cross(v1, v2), cross(v2, v0), cross(v0, v1));  // columns: e = d * c
  vec3 lc = lambda_at(pix, c);
  float z = lc.x * v0.z + lc.y * v1.z + lc.z * v2.z;
  // UV derivatives per pixel from the plane barycentrics one pixel to the right and below.
  vec3 lx = lambda_at(pix + vec2(1.0, 0.0), c);
  vec3 ly = lambda_at(pix + vec2(0.0, 1.0), c);
  const mat3x2 uvs = mat3x2(uv01.xy, uv01.zw, uv2);
  vec2 uvc = uvs * lc;
  vec2 dx = uvs * lx - uvc;
  vec2 dy = uvs * ly - uvc;
  vec3 albedo = vec3(1.0);
  if (m.tex.x != kSimNoTexture) {
    const bool rays4 = pc.misc.y > 1.5;
    Lookup k = lookup_of(m, (rays4 ? 0.5 : 1.0) * dx, (rays4 ? 0.5 : 1.0) * dy);
    if (rays4) {
      albedo = vec3(0.0);
      for (uint r = 0u; r < 4u; ++r) {
        vec2 o = vec2((r & 1u) == 0u ? -0.25 : 0.25, (r & 2u) == 0u ? -0.25 : 0.25);
        albedo += 0.25 * sample_tex(k, uvs * lambda_at(pix + o, c));
      }
    } else {
      albedo = sample_tex(k, uvc);
    }
  }
  albedo *= m.factor.rgb;
  // Face normal in the camera frame, turned towards the camera, then to world (n_w = R^T n_c).
  vec3 nc = cross(v1 - v0, v2 - v0);
  if (dot(nc, v0) > 0.0) nc = -nc;
  float len = length(nc);
  nc = len > 0.0 ? nc / len : vec3(0.0, 0.0, -1.0);
  vec3 nw = nc.x * pc.r0.xyz + nc.y * pc.r1.xyz + nc.z * pc.r2.xyz;
  float lambert = max(dot(nw, pc.light.xyz), 0.0);
  float shade = pc.light.w + (1.0 - pc.light.w) * lambert;
  image[p] = vec4(albedo * shade, z);
}
