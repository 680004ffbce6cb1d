#version 450
// Per triangle: camera-space vertices, the pixel range its (near-clipped) projection can cover,
// and the number of 16x16 raster tiles over that range (none for a small triangle).
#extension GL_GOOGLE_include_directive : require
#include "sim/sim_layout.h"
#include "common/dispatch.glsl"
#include "sim/raster_common.glsl"
layout(local_size_x = kSimSetupGroupSize) in;
layout(std430, binding = kSimTriSetupBindTris) readonly buffer Tris { SimTriangle tris[]; };
layout(std430, binding = kSimTriSetupBindCamVerts) writeonly buffer CamVerts { vec4 cam[]; };  // 3 per triangle
layout(std430, binding = kSimTriSetupBindBoxes) writeonly buffer Boxes { uvec4 boxes[]; };     // x0 y0 x1 y1 (inclusive)
layout(std430, binding = kSimTriSetupBindCounts) writeonly buffer Counts { uint counts[]; };
layout(push_constant) uniform PC { SimPC pc; };

vec3 to_cam(vec3 p) { return vec3(dot(pc.r0.xyz, p) + pc.r0.w, dot(pc.r1.xyz, p) + pc.r1.w, dot(pc.r2.xyz, p) + pc.r2.w); }

void main() {
  uint i = evf_linear_invocation(64u);
  if (i >= pc.dims.z) return;
  vec3 v[3];
  v[0] = to_cam(tris[i].p0.xyz);
  v[1] = to_cam(tris[i].p1.xyz);
  v[2] = to_cam(tris[i].p2.xyz);
  cam[3 * i + 0] = vec4(v[0], 0.0);
  cam[3 * i + 1] = vec4(v[1], 0.0);
  cam[3 * i + 2] = vec4(v[2], 0.0);
  float near = pc.misc.x;
  // Clip the triangle against z >= near (Sutherland-Hodgman, one plane: at most 4 vertices) and
  // bound the projections of the clipped polygon.
  vec2 lo = vec2(1e30), hi = vec2(-1e30);
  uint kept = 0u;
  for (uint k = 0u; k < 3u; ++k) {
    vec3 a = v[k], b = v[(k + 1u) % 3u];
    bool ina = a.z >= near, inb = b.z >= near;
    if (ina) {
      vec2 q = vec2(pc.intr.x * a.x / a.z + pc.intr.z, pc.intr.y * a.y / a.z + pc.intr.w);
      lo = min(lo, q); hi = max(hi, q); ++kept;
    }
    if (ina != inb) {
      float s = (near - a.z) / (b.z - a.z);
      vec3 c = mix(a, b, s);
      vec2 q = vec2(pc.intr.x * c.x / near + pc.intr.z, pc.intr.y * c.y / near + pc.intr.w);
      lo = min(lo, q); hi = max(hi, q); ++kept;
    }
  }
  uint count = 0u;
  uvec4 box = uvec4(1u, 1u, 0u, 0u);
  float W = float(pc.dims.x), H = float(pc.dims.y);
  if (kept > 0u && hi.x >= -1.0 && hi.y >= -1.0 && lo.x <= W + 1.0 && lo.y <= H + 1.0) {
    // Pixel centres x + 0.5 in [lo, hi], widened by 1/16 pixel against the rounding of the
    // projections (about 1e-4 pixel; the exact test runs per pixel). A wider margin costs the
    // small triangles of heavy meshes: a 1-pixel margin made a sub-pixel triangle's box 3 x 3.
    const float margin = 0.0625;
    lo = clamp(lo, vec2(-2.0), vec2(W + 2.0, H + 2.0));
    hi = clamp(hi, vec2(-2.0), vec2(W + 2.0, H + 2.0));
    int x0 = max(int(ceil(lo.x - 0.5 - margin)), 0), y0 = max(int(ceil(lo.y - 0.5 - margin)), 0);
    int x1 = min(int(floor(hi.x - 0.5 + margin)), int(pc.dims.x) - 1);
    int y1 = min(int(floor(hi.y - 0.5 + margin)), int(pc.dims.y) - 1);
    if (x0 <= x1 && y0 <= y1) {
      box = uvec4(x0, y0, x1, y1);
      count = (uint(x1) / kSimTile - uint(x0) / kSimTile + 1u) * (uint(y1) / kSimTile - uint(y0) / kSimTile + 1u);
    }
  }
  boxes[i] = box;
  counts[i] = sim_small_box(box, pc.misc.z) ? 0u : count;  // small ones: sim/raster_small
}
