// Ray through a pixel centre against a camera-space triangle (watertight scalar triple products).
// Returns true when covered in front of the near plane; lambda: perspective-correct barycentrics.
vec3 sim_ray(SimPC pc, vec2 pixel) {
  return vec3((pixel.x - pc.intr.z) / pc.intr.x, (pixel.y - pc.intr.w) / pc.intr.y, 1.0);
}
bool sim_hit(vec3 d, vec3 v0, vec3 v1, vec3 v2, float near, out vec3 lambda, out float z) {
  precise vec3 c0 = cross(v1, v2);
  precise vec3 c1 = cross(v2, v0);
  precise vec3 c2 = cross(v0, v1);
  precise float e0 = d.x * c0.x + d.y * c0.y + d.z * c0.z;
  precise float e1 = d.x * c1.x + d.y * c1.y + d.z * c1.z;
  precise float e2 = d.x * c2.x + d.y * c2.y + d.z * c2.z;
  bool pos = e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
  bool neg = e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0;
  float s = e0 + e1 + e2;
  lambda = vec3(0.0);
  z = 0.0;
  if (!(pos || neg) || s == 0.0) return false;
  lambda = vec3(e0, e1, e2) / s;
  z = lambda.x * v0.z + lambda.y * v1.z + lambda.z * v2.z;
  return z > near;
}
// A triangle whose pixel box (x0 y0 x1 y1, inclusive) spans at most `limit` pixels each way
// (pc.misc.z) is rasterized by sim/raster_small and gets no 16x16 tiles. An empty box is not small.
bool sim_small_box(uvec4 box, float limit) {
  return box.x <= box.z && box.y <= box.w && float(box.z - box.x) < limit && float(box.w - box.y) < limit;
}
