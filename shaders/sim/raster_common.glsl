// Ray through a pixel centre against a camera-space triangle (watertight scalar triple products).
// Returns true when covered in front of the near plane; lambda: perspective-correct barycentrics.
vec3 sim_ray(SimPC pc, vec2 pixel) {
  return vec3((pixel.x - pc.intr.z) / pc.intr.x, (pixel.y - pc.intr.w) / pc.intr.y, 1.0);
}
// A triangle's vertex crosses and depths: what every pixel's test reads, found once a triangle.
struct SimEdges {
  vec3 c0, c1, c2;
  vec3 z;  // the vertices' camera z
};
SimEdges sim_edges(vec3 v0, vec3 v1, vec3 v2) {
  SimEdges t;
  precise vec3 c0 = cross(v1, v2);
  precise vec3 c1 = cross(v2, v0);
  precise vec3 c2 = cross(v0, v1);
  t.c0 = c0;
  t.c1 = c1;
  t.c2 = c2;
  t.z = vec3(v0.z, v1.z, v2.z);
  return t;
}
bool sim_hit(vec3 d, SimEdges t, float near, out vec3 lambda, out float z) {
  precise float e0 = d.x * t.c0.x + d.y * t.c0.y + d.z * t.c0.z;
  precise float e1 = d.x * t.c1.x + d.y * t.c1.y + d.z * t.c1.z;
  precise float e2 = d.x * t.c2.x + d.y * t.c2.y + d.z * t.c2.z;
  bool pos = e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
  bool neg = e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0;
  float s = e0 + e1 + e2;
  lambda = vec3(0.0);
  z = 0.0;
  if (!(pos || neg) || s == 0.0) return false;
  lambda = vec3(e0, e1, e2) / s;
  z = lambda.x * t.z.x + lambda.y * t.z.y + lambda.z * t.z.z;
  return z > near;
}
// A triangle whose pixel box (x0 y0 x1 y1, inclusive) spans at most `limit` pixels each way
// (pc.misc.z) is rasterized by sim/raster_small and gets no 16x16 tiles. An empty box is not small.
bool sim_small_box(uvec4 box, float limit) {
  return box.x <= box.z && box.y <= box.w && float(box.z - box.x) < limit && float(box.w - box.y) < limit;
}
