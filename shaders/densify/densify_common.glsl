// Helpers shared by the densify kernels.
float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }

// Rotation matrix of a (normalised here) wxyz quaternion; columns are the local axes.
mat3 quat_to_mat(vec4 q) {
  float n = length(q);
  q = n > 0.0 ? q / n : vec4(1.0, 0.0, 0.0, 0.0);
  float w = q.x, x = q.y, y = q.z, z = q.w;
  // GLSL mat3(c0, c1, c2): column-major.
  return mat3(vec3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)),
              vec3(2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z + w * x)),
              vec3(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)));
}

// Extra rows a Gaussian adds when its growth is granted (see densify_layout.h).
uint extra_rows(uint dec) {
  if ((dec & kDecClone) != 0u) return 1u;
  if ((dec & kDecSplit) != 0u) return (dec & kDecKeep) != 0u ? 1u : 2u;
  return 0u;
}
uint out_rows(uint dec) {
  uint base = (dec & kDecKeep) != 0u ? 1u : 0u;
  return base + ((dec & kDecGrown) != 0u ? extra_rows(dec) : 0u);
}

// PCG hash (O'Neill): a stateless, deterministic integer hash.
uint pcg_hash(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
// Uniform in (0, 1) from 24 bits.
float unit_uniform(uint h) { return (float(h >> 8u) + 0.5) * (1.0 / 16777216.0); }
