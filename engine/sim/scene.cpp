#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace evflow::sim {

std::array<float, 3> Scene::bounds_min() const {
  std::array<float, 3> b{INFINITY, INFINITY, INFINITY};
  for (size_t i = 0; i < positions.size(); ++i) b[i % 3] = std::min(b[i % 3], positions[i]);
  return b;
}
std::array<float, 3> Scene::bounds_max() const {
  std::array<float, 3> b{-INFINITY, -INFINITY, -INFINITY};
  for (size_t i = 0; i < positions.size(); ++i) b[i % 3] = std::max(b[i % 3], positions[i]);
  return b;
}

void Scene::add_quad(const std::array<float, 3>& p0, const std::array<float, 3>& p1, const std::array<float, 3>& p2,
                     const std::array<float, 3>& p3, uint32_t mat, float ur, float vr) {
  const std::array<float, 3>* q[4] = {&p0, &p1, &p2, &p3};
  // UV v grows downwards in glTF (v = 0 at the top of the image): p0 bottom-left -> (0, vr).
  const float uv[4][2] = {{0, vr}, {ur, vr}, {ur, 0}, {0, 0}};
  const int tri[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (auto& t : tri) {
    for (int k : t) {
      for (int c = 0; c < 3; ++c) positions.push_back((*q[k])[c]);
      uvs.push_back(uv[k][0]);
      uvs.push_back(uv[k][1]);
    }
    material.push_back(mat);
  }
}

void Scene::add_box(const std::array<float, 3>& lo, const std::array<float, 3>& hi, uint32_t mat, float s) {
  const float x0 = lo[0], y0 = lo[1], z0 = lo[2], x1 = hi[0], y1 = hi[1], z1 = hi[2];
  const float dx = (x1 - x0) * s, dy = (y1 - y0) * s, dz = (z1 - z0) * s;
  add_quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, mat, dx, dy);  // +z
  add_quad({x1, y0, z0}, {x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, mat, dx, dy);  // -z
  add_quad({x1, y0, z1}, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, mat, dz, dy);  // +x
  add_quad({x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, mat, dz, dy);  // -x
  add_quad({x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}, {x0, y1, z0}, mat, dx, dz);  // +y
  add_quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, mat, dx, dz);  // -y
}

void Scene::validate() const {
  const size_t t = triangle_count();
  if (positions.size() != t * 9 || uvs.size() != t * 6)
    throw std::runtime_error(source + ": inconsistent triangle arrays");
  for (float v : positions)
    if (!std::isfinite(v)) throw std::runtime_error(source + ": non-finite vertex position");
  for (float v : uvs)
    if (!std::isfinite(v)) throw std::runtime_error(source + ": non-finite texture coordinate");
  for (uint32_t m : material)
    if (m >= materials.size()) throw std::runtime_error(source + ": triangle material index out of range");
  for (auto& m : materials)
    if (m.texture >= int(textures.size())) throw std::runtime_error(source + ": material texture index out of range");
  for (auto& tx : textures)
    if (tx.width == 0 || tx.height == 0 || tx.rgba.size() != size_t(tx.width) * tx.height)
      throw std::runtime_error(source + ": texture '" + tx.name + "' has inconsistent size");
}

}  // namespace evflow::sim
