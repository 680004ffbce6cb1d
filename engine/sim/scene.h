// Scenes of the simulator: world-space triangle soups with base-colour materials, read from
// glTF 2.0 (sim/gltf_scene.h) or made procedurally (sim/builtin_scenes.h).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace evflow::sim {

// An RGBA8 texture, sRGB-encoded colour (as glTF stores base-colour textures), row-major, top row first.
struct Texture {
  std::string name;
  uint32_t width = 0, height = 0;
  std::vector<uint32_t> rgba;  // packed R | G << 8 | B << 16 | A << 24
  enum Wrap : uint32_t { Repeat = 0, Clamp = 1, Mirror = 2 };
  uint32_t wrap_s = Repeat, wrap_t = Repeat;
};

struct Material {
  std::string name;
  std::array<float, 4> base_color{1, 1, 1, 1};  // linear RGBA factor
  int texture = -1;                             // index into Scene::textures, -1 = none
};

// Triangles in world space (glTF convention: y up, right-handed; units arbitrary).
struct Scene {
  std::string source;              // file name or "default"
  std::vector<float> positions;    // [T][3][3]
  std::vector<float> uvs;          // [T][3][2]
  std::vector<uint32_t> material;  // [T]
  std::vector<Material> materials;
  std::vector<Texture> textures;
  // Optional camera-rig hint (the default scene sets it): cameras circle `view_target` at
  // `view_radius`; when unset the rig is derived from the bounds.
  bool has_view_hint = false;
  std::array<float, 3> view_target{0, 0, 0};
  float view_radius = 0, view_height = 0;

  size_t triangle_count() const { return material.size(); }
  // Axis-aligned bounds of all vertices.
  std::array<float, 3> bounds_min() const;
  std::array<float, 3> bounds_max() const;
  // Appends a textured quad p0 p1 p2 p3 (counter-clockwise), UVs (0,0) at p0 .. (u_repeat, v_repeat) at p2.
  void add_quad(const std::array<float, 3>& p0, const std::array<float, 3>& p1, const std::array<float, 3>& p2,
                const std::array<float, 3>& p3, uint32_t material, float u_repeat = 1, float v_repeat = 1);
  // Appends an axis-aligned box (6 quads) with one material.
  void add_box(const std::array<float, 3>& lo, const std::array<float, 3>& hi, uint32_t material, float uv_scale = 1);
  // Throws std::runtime_error naming `source` on inconsistent arrays or non-finite values.
  void validate() const;
};

// The same surfaces as `scene` with every triangle split into k x k triangles (a regular grid in
// barycentric coordinates; UVs interpolated alike): a heavier mesh of the same images. The points
// on an edge are computed the same way from both triangles that share it (float-exact), so a
// watertight mesh stays watertight. k >= 1; k = 1 returns a copy.
Scene subdivide(const Scene& scene, int k);

}  // namespace evflow::sim
