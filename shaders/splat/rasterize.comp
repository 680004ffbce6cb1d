#version 450
// Forward rasterization: one workgroup per 16x16 tile, one invocation per pixel. The tile's
// Gaussians (front to back) are loaded 256 at a time into shared memory; each pixel blends
// them until its transmittance would fall below 1e-4. The workgroup leaves early once every
// pixel is done.
#extension GL_GOOGLE_include_directive : require
#include "splat/splat_layout.h"
#include "common/dispatch.glsl"
#include "splat/splat_math.glsl"
layout(local_size_x = kTileSize, local_size_y = kTileSize) in;
#include "splat/raster_io.glsl"
layout(std430, binding = kRasterizeBindOutRgb) writeonly buffer OutRgb { float out_rgb[]; };        // [3][H][W]
layout(std430, binding = kRasterizeBindOutAlpha) writeonly buffer OutAlpha { float out_alpha[]; };  // [H][W]
layout(std430, binding = kRasterizeBindOutDepth) writeonly buffer OutDepth { float out_depth[]; };  // [H][W]
layout(std430, binding = kRasterizeBindOutT) writeonly buffer OutT { float final_T[]; };            // [H][W]
layout(std430, binding = kRasterizeBindOutLast) writeonly buffer OutLast { uint last_isect[]; };    // [H][W] one past the last blended
layout(push_constant) uniform PC { RasterPC pc; };
shared uint done_count;

void main() {
  ivec2 tile = tile_of_group(pc.tiles_x);
  ivec2 pix = tile * int(kTileSize) + ivec2(gl_LocalInvocationID.xy);
  bool inside = pix.x < int(pc.width) && pix.y < int(pc.height);
  vec2 centre = vec2(pix) + 0.5;
  uvec2 range = tile_range[tile.y * pc.tiles_x + tile.x];
  float T = 1.0;
  vec3 C = vec3(0.0);
  float D = 0.0;
  uint last = range.x;
  bool done = !inside;
  uint lid = gl_LocalInvocationIndex;
  for (uint start = range.x; start < range.y; start += 256u) {
    barrier();
    if (lid == 0) done_count = 0;
    if (start + lid < range.y) load_batch_entry(lid, start + lid);
    barrier();
    if (done) atomicAdd(done_count, 1u);
    barrier();
    if (done_count == 256u) break;
    uint n = min(256u, range.y - start);
    for (uint j = 0; j < n && !done; ++j) {
      vec4 a = batch_mean_conic[j], b = batch_misc[j];
      vec3 conic = vec3(a.zw, b.x);
      float power = splat_power(conic, a.xy - centre);
      float alpha = min(kAlphaMax, b.y * exp(power));
      if (alpha < kAlphaMin) continue;
      float next_T = T * (1.0 - alpha);
      if (next_T < kTransmittanceMin) { done = true; break; }
      float w = alpha * T;
      C += w * batch_color[j];
      D += w * b.z;
      T = next_T;
      last = start + j + 1;
    }
  }
  if (!inside) return;
  uint hw = pc.width * pc.height, i = uint(pix.y) * pc.width + uint(pix.x);
  vec3 rgb = C + T * pc.background.rgb;
  out_rgb[i] = rgb.r;
  out_rgb[hw + i] = rgb.g;
  out_rgb[2 * hw + i] = rgb.b;
  out_alpha[i] = 1.0 - T;
  out_depth[i] = (T < 1.0) ? D / (1.0 - T) : 0.0;
  final_T[i] = T;
  last_isect[i] = last;
}
