// The buffers of the raster passes and one pixel's test, shared by sim/raster (a 16x16 workgroup
// per tile of a triangle) and sim/raster_small (one invocation per small triangle).
layout(std430, binding = kSimRasterBindCamVerts) readonly buffer CamVerts { vec4 cam[]; };
layout(std430, binding = kSimRasterBindBoxes) readonly buffer Boxes { uvec4 boxes[]; };
layout(std430, binding = kSimRasterBindDepth) buffer Depth { uint depth[]; };
layout(std430, binding = kSimRasterBindIds) buffer Ids { uint ids[]; };
layout(push_constant) uniform PC { SimPC pc; };

// Pixel (x, y) against triangle `tri` (its edges found once by the caller). Mode 0 (pc.dims.w):
// atomicMin of the depth bits (positive floats order like uints).
// Mode 1: atomicMin of the triangle id where the depth is the minimum.
void sim_raster_pixel(uint tri, SimEdges t, uint x, uint y) {
  vec3 lambda;
  float z;
  vec3 d = sim_ray(pc, vec2(x, y) + 0.5);
  if (!sim_hit(d, t, pc.misc.x, lambda, z)) return;
  uint p = y * pc.dims.x + x;
  uint bits = floatBitsToUint(z);
  if (pc.dims.w == 0u) atomicMin(depth[p], bits);
  else if (depth[p] == bits) atomicMin(ids[p], tri);
}
