// Buffers shared by rasterize and rasterize_bwd (bindings 0..5), and the batch of Gaussians a
// tile's workgroup holds in shared memory.
layout(std430, binding = 0) readonly buffer Ranges { uvec2 tile_range[]; };
layout(std430, binding = 1) readonly buffer Slots { uint slot_from_isect[]; };     // sorted
layout(std430, binding = 2) readonly buffer Gid { uint gaussian_id_from_slot[]; };
layout(std430, binding = 3) readonly buffer ProjA { vec4 proj_mean_conic[]; };
layout(std430, binding = 4) readonly buffer ProjB { vec4 proj_misc[]; };
layout(std430, binding = 5) readonly buffer ProjC { vec4 proj_color[]; };

shared vec4 batch_mean_conic[256];  // mean.xy, conic.xy
shared vec4 batch_misc[256];        // conic.z, opacity, depth, -
shared vec3 batch_color[256];
shared uint batch_slot[256];

void load_batch_entry(uint local, uint isect) {
  uint slot = slot_from_isect[isect];
  uint g = gaussian_id_from_slot[slot];
  batch_slot[local] = slot;
  batch_mean_conic[local] = proj_mean_conic[g];
  batch_misc[local] = proj_misc[g];
  batch_color[local] = proj_color[g].rgb;
}

ivec2 tile_of_group(uint tiles_x) {
  uint t = evf_linear_group();
  return ivec2(t % tiles_x, t / tiles_x);
}
