#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

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

namespace {

// The point of barycentric grid coordinates (i, j) of triangle (a, b, c), `dims` floats per vertex.
// (wa*a + wb*b) + wc*c: on an edge one weight is zero and the sum is one of two terms, which float
// addition gives identically in either order, so both triangles of a shared edge agree bit for bit.
void grid_point(const float* v, int dims, int k, int i, int j, std::vector<float>& out) {
  const float wa = float(k - i - j), wb = float(i), wc = float(j);
  for (int d = 0; d < dims; ++d) out.push_back(((wa * v[d] + wb * v[dims + d]) + wc * v[2 * dims + d]) / float(k));
}

}  // namespace

Scene subdivide(const Scene& scene, int k) {
  if (k < 1) throw std::invalid_argument("subdivide: k must be at least 1, got " + std::to_string(k));
  Scene out = scene;
  out.positions.clear();
  out.uvs.clear();
  out.material.clear();
  const size_t T = scene.triangle_count();
  out.positions.reserve(T * k * k * 9);
  out.uvs.reserve(T * k * k * 6);
  out.material.reserve(T * k * k);
  for (size_t t = 0; t < T; ++t) {
    const float* p = &scene.positions[t * 9];
    const float* uv = &scene.uvs[t * 6];
    auto emit = [&](int i0, int j0, int i1, int j1, int i2, int j2) {
      for (auto [i, j] : {std::pair{i0, j0}, std::pair{i1, j1}, std::pair{i2, j2}}) {
        grid_point(p, 3, k, i, j, out.positions);
        grid_point(uv, 2, k, i, j, out.uvs);
      }
      out.material.push_back(scene.material[t]);
    };
    // Same winding as (a, b, c): upward cells, then the downward ones between them.
    for (int j = 0; j < k; ++j)
      for (int i = 0; i + j < k; ++i) {
        emit(i, j, i + 1, j, i, j + 1);
        if (i + j + 2 <= k) emit(i + 1, j, i + 1, j + 1, i, j + 1);
      }
  }
  return out;
}

}  // namespace evflow::sim
