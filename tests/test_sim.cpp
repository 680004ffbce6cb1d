// [sim]: the dataset simulator (engine/sim): mesh renderer, glTF scenes, shake blur, sub-frame
// bound, ground-truth flow, event/EDI consistency and the written dataset.
#include <catch2/catch.hpp>

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "events/edi.h"
#include "gpu_fixture.h"
#include "io/dataset.h"
#include "io/image.h"
#include "sim/builtin_scenes.h"
#include "sim/gltf_scene.h"
#include "sim/mesh_renderer.h"
#include "sim/scene.h"
#include "sim/simulation_writer.h"
#include "sim/simulator.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("evflow_test_sim_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

Camera identity_camera(uint32_t W, uint32_t H) {
  Camera c;
  c.width = W;
  c.height = H;
  c.fx = c.fy = 100;
  c.cx = 48;
  c.cy = 36;
  return c;
}

// World point (camera = identity) at pixel position (u, v) and depth z.
std::array<float, 3> at_pixel(const Camera& c, double u, double v, double z) {
  return {float((u - c.cx) * z / c.fx), float((v - c.cy) * z / c.fy), float(z)};
}

void push_tri(sim::Scene& s, std::array<float, 3> a, std::array<float, 3> b, std::array<float, 3> c,
              std::array<float, 6> uv, uint32_t mat) {
  for (auto* p : {&a, &b, &c}) s.positions.insert(s.positions.end(), p->begin(), p->end());
  s.uvs.insert(s.uvs.end(), uv.begin(), uv.end());
  s.material.push_back(mat);
}

uint8_t srgb_byte(int i, int j, int c) { return uint8_t(c == 0 ? 6 * i : c == 1 ? 6 * j : 200 - 3 * (i + j)); }

}  // namespace

TEST_CASE("sim renderer: quad coverage (pixel centres), depth and texture lookup", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 96, H = 72;
  const Camera cam = identity_camera(W, H);
  sim::Scene s;
  s.source = "quad";
  // 40 x 40 texture mapped texel-to-pixel onto pixels [20, 60) x [10, 50) at depth 2.
  sim::Texture t;
  t.width = t.height = 40;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i)
      t.rgba.push_back(srgb_byte(i, j, 0) | srgb_byte(i, j, 1) << 8 | uint32_t(srgb_byte(i, j, 2)) << 16 | 0xFF000000u);
  s.textures.push_back(t);
  s.materials.push_back(sim::Material{"tex", {1, 1, 1, 1}, 0});
  const auto p00 = at_pixel(cam, 20, 10, 2), p10 = at_pixel(cam, 60, 10, 2), p11 = at_pixel(cam, 60, 50, 2),
             p01 = at_pixel(cam, 20, 50, 2);
  push_tri(s, p00, p10, p11, {0, 0, 1, 0, 1, 1}, 0);
  push_tri(s, p00, p11, p01, {0, 0, 1, 1, 0, 1}, 0);
  // A slanted triangle behind it (partly hidden) with vertices off the pixel grid.
  s.materials.push_back(sim::Material{"flat", {0.5f, 0.25f, 0.125f, 1}, -1});
  const std::array<float, 3> q0 = at_pixel(cam, 5.3, 3.7, 3), q1 = at_pixel(cam, 90.2, 20.1, 5),
                             q2 = at_pixel(cam, 30.6, 68.4, 4);
  push_tri(s, q0, q1, q2, {0, 0, 0, 0, 0, 0}, 1);
  sim::ShadingParams sh;
  sh.ambient = 1.0f;
  sh.texture_samples = 1;
  sh.background = {0.1f, 0.2f, 0.3f};
  sim::MeshRenderer r(ctx, s, sh);
  const sim::Frame f = r.render(cam);
  // Reference coverage of the slanted triangle from its projected 2D vertices (skip centres on an edge).
  const double X[3][2] = {{5.3, 3.7}, {90.2, 20.1}, {30.6, 68.4}};
  auto edge = [&](int a, int b, double x, double y) {
    return (X[b][0] - X[a][0]) * (y - X[a][1]) - (X[b][1] - X[a][1]) * (x - X[a][0]);
  };
  // Plane of the slanted triangle: depth along each pixel ray (double).
  auto plane_depth = [&](double u, double v) {
    const double d[3] = {(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1};
    const double a[3] = {q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]},
                 b[3] = {q2[0] - q0[0], q2[1] - q0[1], q2[2] - q0[2]};
    const double n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    return (n[0] * q0[0] + n[1] * q0[1] + n[2] * q0[2]) / (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
  };
  int mismatches = 0, covered_quad = 0, covered_tri = 0;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const size_t p = size_t(y) * W + x;
      const double u = x + 0.5, v = y + 0.5;
      const bool in_quad = x >= 20 && x < 60 && y >= 10 && y < 50;
      const double e0 = edge(0, 1, u, v), e1 = edge(1, 2, u, v), e2 = edge(2, 0, u, v);
      const bool on_edge = std::min({std::abs(e0), std::abs(e1), std::abs(e2)}) < 1e-2;
      const bool in_tri = (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
      if (in_quad) {
        ++covered_quad;
        REQUIRE(f.depth[p] == Approx(2.0).epsilon(1e-6));
        const int i = x - 20, j = y - 10;
        for (int c = 0; c < 3; ++c)
          REQUIRE(f.rgb[p * 3 + c] == Approx(io::srgb_to_linear(srgb_byte(i, j, c) / 255.f)).margin(2e-4));
      } else if (on_edge) {
        continue;
      } else if (in_tri) {
        ++covered_tri;
        if (!(std::abs(f.depth[p] - plane_depth(u, v)) < 1e-4 * plane_depth(u, v))) ++mismatches;
        if (std::abs(f.rgb[p * 3] - 0.5f) > 1e-6 || std::abs(f.rgb[p * 3 + 2] - 0.125f) > 1e-6) ++mismatches;
      } else {
        if (f.depth[p] != 0.f || f.rgb[p * 3] != 0.1f || f.rgb[p * 3 + 2] != 0.3f) ++mismatches;
      }
    }
  CHECK(covered_quad == 1600);
  CHECK(covered_tri > 500);
  CHECK(mismatches == 0);
  test::require_no_validation_messages();
}

// The shading's trilinear lookup in double: the renderer's mip chain (2 x 2 box in linear light,
// re-encoded to sRGB bytes), bilinear taps with repeat (s) and mirrored repeat (t) wrapping.
struct TrilinearReference {
  std::vector<std::vector<uint32_t>> levels;
  std::vector<int> w, h;
  explicit TrilinearReference(const sim::Texture& t) {
    levels.push_back(t.rgba);
    w.push_back(int(t.width));
    h.push_back(int(t.height));
    while (w.back() > 1 || h.back() > 1) {
      const int pw = w.back(), ph = h.back(), nw = std::max(1, pw / 2), nh = std::max(1, ph / 2);
      std::vector<uint32_t> next(size_t(nw) * nh);
      for (int y = 0; y < nh; ++y)
        for (int x = 0; x < nw; ++x)
          for (int k = 0; k < 3; ++k) {
            float acc = 0;
            for (int d = 0; d < 4; ++d) {
              const int sx = std::min(2 * x + (d & 1), pw - 1), sy = std::min(2 * y + (d >> 1), ph - 1);
              acc += io::srgb_to_linear(((levels.back()[size_t(sy) * pw + sx] >> (8 * k)) & 255u) / 255.f);
            }
            const float v = std::clamp(io::linear_to_srgb(0.25f * acc), 0.f, 1.f);
            next[size_t(y) * nw + x] |= uint32_t(std::lround(v * 255.f)) << (8 * k);
          }
      levels.push_back(next);
      w.push_back(nw);
      h.push_back(nh);
    }
  }
  double texel(int l, int x, int y, int c) const {
    auto mod = [](int i, int n) { return ((i % n) + n) % n; };
    x = mod(x, w[l]);
    y = mod(y, 2 * h[l]);
    if (y >= h[l]) y = 2 * h[l] - 1 - y;
    return io::srgb_to_linear(((levels[l][size_t(y) * w[l] + x] >> (8 * c)) & 255u) / 255.f);
  }
  double bilinear(int l, double u, double v, int c) const {
    const double fx = u * w[l] - 0.5, fy = v * h[l] - 0.5, x0 = std::floor(fx), y0 = std::floor(fy);
    const double ax = fx - x0, ay = fy - y0;
    const int x = int(x0), y = int(y0);
    const double top = (1 - ax) * texel(l, x, y, c) + ax * texel(l, x + 1, y, c);
    const double bottom = (1 - ax) * texel(l, x, y + 1, c) + ax * texel(l, x + 1, y + 1, c);
    return (1 - ay) * top + ay * bottom;
  }
  // footprint: texels per sample
  double trilinear(double u, double v, double footprint, int c) const {
    const double lod = std::clamp(std::log2(footprint), 0.0, double(levels.size() - 1));
    const int l0 = int(std::floor(lod)), l1 = std::min(l0 + 1, int(levels.size()) - 1);
    const double t = lod - l0;
    return (1 - t) * bilinear(l0, u, v, c) + t * bilinear(l1, u, v, c);
  }
};

TEST_CASE("sim renderer: four rays a pixel on a minified texture blend two mip levels as a trilinear reference",
          "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 96, H = 72;
  const Camera cam = identity_camera(W, H);
  sim::Scene s;
  s.source = "minified quad";
  // A 60 x 60 texture on pixels [20, 40) x [10, 30): 3 texels a pixel, 1.5 a ray of four, so the
  // lookup blends levels 0 and 1 (lod log2 1.5).
  sim::Texture t;
  t.width = t.height = 60;
  t.wrap_t = sim::Texture::Mirror;
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 60; ++i)
      t.rgba.push_back(uint32_t((4 * i) & 255) | uint32_t((4 * j) & 255) << 8 | uint32_t((17 * (i ^ j)) & 255) << 16 |
                       0xFF000000u);
  s.textures.push_back(t);
  s.materials.push_back(sim::Material{"tex", {1, 1, 1, 1}, 0});
  push_tri(s, at_pixel(cam, 20, 10, 2), at_pixel(cam, 40, 10, 2), at_pixel(cam, 40, 30, 2), {0, 0, 1, 0, 1, 1}, 0);
  push_tri(s, at_pixel(cam, 20, 10, 2), at_pixel(cam, 40, 30, 2), at_pixel(cam, 20, 30, 2), {0, 0, 1, 1, 0, 1}, 0);
  sim::ShadingParams sh;
  sh.ambient = 1.0f;
  sh.texture_samples = 4;
  const sim::Frame f = sim::MeshRenderer(ctx, s, sh).render(cam);
  const TrilinearReference ref(t);
  REQUIRE(ref.levels.size() == 6);
  double worst = 0;
  for (uint32_t y = 10; y < 30; ++y)
    for (uint32_t x = 20; x < 40; ++x)
      for (int c = 0; c < 3; ++c) {
        double want = 0;
        for (int r = 0; r < 4; ++r) {
          const double px = x + 0.5 + ((r & 1) ? 0.25 : -0.25), py = y + 0.5 + ((r & 2) ? 0.25 : -0.25);
          want += 0.25 * ref.trilinear((px - 20) / 20, (py - 10) / 20, 1.5, c);
        }
        worst = std::max(worst, std::abs(f.rgb[(size_t(y) * W + x) * 3 + c] - want));
      }
  CHECK(worst < 1e-4);
  test::require_no_validation_messages();
}

TEST_CASE("sim renderer: a triangle through the near plane and a screen-filling triangle", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 96, H = 72;
  Camera cam = identity_camera(W, H);
  cam.near_plane = 0.1;
  sim::Scene s;
  s.source = "big";
  s.materials.push_back(sim::Material{"white", {1, 1, 1, 1}, -1});
  // Floor-like triangle from behind the camera to far away (crosses the near plane).
  push_tri(s, {-50, 1, -5}, {50, 1, -5}, {0, 1, 100}, {0, 0, 0, 0, 0, 0}, 0);
  sim::ShadingParams sh;
  sh.ambient = 1.0f;
  sim::MeshRenderer r(ctx, s, sh);
  const sim::Frame f = r.render(cam);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const double v = y + 0.5;
      const double dy = (v - cam.cy) / cam.fy;  // ray y per unit z; hits y = 1 at z = 1 / dy
      const float d = f.depth[size_t(y) * W + x];
      if (dy > 0.02) {  // well below the horizon (z < 50): covered
        REQUIRE(d == Approx(1.0 / dy).epsilon(1e-4));
      } else if (dy <= 0) {
        REQUIRE(d == 0.f);
      }
    }
  test::require_no_validation_messages();
}

TEST_CASE("sim glTF: a user glTF with a texture loads and renders, bad files give clear errors", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const fs::path dir = temp_dir("gltf");
  // A unit quad (x, y in [-1, 1], z = 0) under a node translated to z = -3, 2x2 texture
  // (red, green / blue, white), non-indexed.
  tinygltf::Model m;
  m.asset.version = "2.0";
  const float pos[18] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, -1, 0, 1, 1, 0, -1, 1, 0};
  const float uv[12] = {0, 1, 1, 1, 1, 0, 0, 1, 1, 0, 0, 0};
  tinygltf::Buffer buf;
  buf.data.resize(sizeof pos + sizeof uv);
  std::memcpy(buf.data.data(), pos, sizeof pos);
  std::memcpy(buf.data.data() + sizeof pos, uv, sizeof uv);
  m.buffers.push_back(buf);
  for (int k = 0; k < 2; ++k) {
    tinygltf::BufferView bv;
    bv.buffer = 0;
    bv.byteOffset = k ? sizeof pos : 0;
    bv.byteLength = k ? sizeof uv : sizeof pos;
    m.bufferViews.push_back(bv);
    tinygltf::Accessor a;
    a.bufferView = k;
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = 6;
    a.type = k ? TINYGLTF_TYPE_VEC2 : TINYGLTF_TYPE_VEC3;
    if (!k) {
      a.minValues = {-1, -1, 0};
      a.maxValues = {1, 1, 0};
    }
    m.accessors.push_back(a);
  }
  tinygltf::Image img;
  img.width = img.height = 2;
  img.component = 4;
  img.bits = 8;
  img.pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
  img.mimeType = "image/png";
  img.image = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  m.images.push_back(img);
  tinygltf::Sampler smp;
  smp.wrapS = smp.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  m.samplers.push_back(smp);
  tinygltf::Texture tex;
  tex.source = 0;
  tex.sampler = 0;
  m.textures.push_back(tex);
  tinygltf::Material mat;
  mat.pbrMetallicRoughness.baseColorTexture.index = 0;
  m.materials.push_back(mat);
  tinygltf::Primitive prim;
  prim.attributes["POSITION"] = 0;
  prim.attributes["TEXCOORD_0"] = 1;
  prim.material = 0;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(prim);
  m.meshes.push_back(mesh);
  tinygltf::Node child;
  child.mesh = 0;
  child.translation = {0, 0, -3};
  tinygltf::Node root;
  root.children = {1};
  m.nodes = {root, child};
  tinygltf::Scene sc;
  sc.nodes = {0};
  m.scenes.push_back(sc);
  m.defaultScene = 0;
  tinygltf::TinyGLTF w;
  for (const char* name : {"quad.gltf", "quad.glb"}) {
    const fs::path file = dir / name;
    REQUIRE(w.WriteGltfSceneToFile(&m, file.string(), true, true, true,
                                   std::string(name).find(".glb") != std::string::npos));
    const sim::Scene s = sim::load_gltf(file);
    REQUIRE(s.triangle_count() == 2);
    REQUIRE(s.textures.size() == 1);
    REQUIRE(s.textures[0].width == 2);
    CHECK(s.positions[2] == -3.f);
    // Look at the quad from +z (glTF: the camera looks down -z, y up).
    const Camera cam = Camera::look_at(64, 64, 60, {0, 0, 0}, {0, 0, -3});
    sim::ShadingParams sh;
    sh.ambient = 1.0f;
    sim::MeshRenderer r(ctx, s, sh);
    const sim::Frame f = r.render(cam);
    auto px = [&](int x, int y, int c) { return f.rgb[(size_t(y) * 64 + x) * 3 + c]; };
    // Top-left of the image = top-left of the texture (red), top-right green, bottom-left blue.
    CHECK(px(22, 22, 0) > 0.9f);
    CHECK(px(22, 22, 1) < 0.05f);
    CHECK(px(41, 22, 1) > 0.9f);
    CHECK(px(22, 41, 2) > 0.9f);
    CHECK(px(41, 41, 0) > 0.9f);
    CHECK(f.depth[32 * 64 + 32] == Approx(3.0).epsilon(1e-5));
    CHECK(f.depth[2 * 64 + 2] == 0.f);  // outside the quad
  }
  // The default scene survives export -> import and renders identically.
  const fs::path glb = dir / "default.glb";
  const sim::Scene def = sim::make_default_scene();
  sim::write_gltf(def, glb);
  const sim::Scene back = sim::load_gltf(glb);
  REQUIRE(back.triangle_count() == def.triangle_count());
  REQUIRE(back.textures.size() == def.textures.size());
  // The camera-rig hint travels in the scene's extras, so the file simulates from the same cameras.
  REQUIRE(back.has_view_hint);
  CHECK(back.view_target == def.view_target);
  CHECK(back.view_radius == def.view_radius);
  CHECK(back.view_height == def.view_height);
  const Camera cam = Camera::look_at(96, 72, 50, {1.0, 1.0, 3.0}, {0, 0, -1.5});
  sim::MeshRenderer r1(ctx, def), r2(ctx, back);
  const auto f1 = r1.render(cam), f2 = r2.render(cam);
  double diff = 0;
  for (size_t i = 0; i < f1.rgb.size(); ++i) diff = std::max(diff, double(std::abs(f1.rgb[i] - f2.rgb[i])));
  CHECK(diff < 1e-5);
  // Errors name the file.
  auto message = [](const fs::path& p) {
    try {
      sim::load_gltf(p);
    } catch (const std::runtime_error& e) { return std::string(e.what()); }
    return std::string("no error");
  };
  const fs::path missing = dir / "missing.gltf";
  CHECK_THAT(message(missing), Catch::Contains(missing.string()));
  const fs::path bad = dir / "bad.gltf";
  { std::ofstream(bad) << "{ \"asset\": {\"version\": \"2.0\"}, \"meshes\": [ {"; }
  CHECK_THAT(message(bad), Catch::Contains(bad.string()));
  const fs::path trunc = dir / "trunc.glb";
  {
    std::ifstream in(dir / "quad.glb", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(trunc, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  CHECK_THAT(message(trunc), Catch::Contains(trunc.string()));
  const fs::path noidx = dir / "badindex.gltf";
  {
    tinygltf::Model m2 = m;
    m2.meshes[0].primitives[0].attributes["POSITION"] = 7;
    REQUIRE(w.WriteGltfSceneToFile(&m2, noidx.string(), true, true, true, false));
  }
  CHECK_THAT(message(noidx), Catch::Contains(noidx.string()));
  const fs::path badview = dir / "badview.gltf";
  {
    tinygltf::Model m2 = m;
    tinygltf::Value::Object view{{"target", tinygltf::Value(tinygltf::Value::Array(3, tinygltf::Value(0.0)))},
                                 {"radius", tinygltf::Value(-1.0)},
                                 {"height", tinygltf::Value(1.0)}};
    m2.scenes.at(0).extras = tinygltf::Value(tinygltf::Value::Object{{"evflow_view", tinygltf::Value(view)}});
    REQUIRE(w.WriteGltfSceneToFile(&m2, badview.string(), true, true, true, false));
  }
  CHECK_THAT(message(badview), Catch::Contains(badview.string()) && Catch::Contains("'radius' must be positive"));
  fs::remove_all(dir);
  test::require_no_validation_messages();
}

TEST_CASE("sim renderer: a subdivided scene renders the original's image, small triangles as the tiles do",
          "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene def = sim::make_default_scene();
  const sim::Scene sub = sim::subdivide(def, 16);
  REQUIRE(sub.triangle_count() == def.triangle_count() * 256);
  REQUIRE(sim::subdivide(def, 1).positions == def.positions);
  const Camera cam = Camera::look_at(96, 72, 50, {1.0, 1.0, 3.0}, {0, 0, -1.5});
  sim::MeshRenderer orig(ctx, def), small(ctx, sub), tiles(ctx, sub);
  tiles.set_small_triangle_box(0);
  const sim::Frame fo = orig.render(cam), fs_ = small.render(cam), ft = tiles.render(cam);
  // One invocation per small triangle and a workgroup per tile find the same nearest triangle.
  CHECK(fs_.rgb == ft.rgb);
  CHECK(fs_.depth == ft.depth);
  // The same surfaces: coverage, depth and colour as the 72-triangle original.
  size_t covered_differently = 0, depth_off = 0, colour_off = 0;
  for (size_t i = 0; i < fo.depth.size(); ++i) {
    if ((fo.depth[i] > 0) != (fs_.depth[i] > 0)) ++covered_differently;
    if (std::abs(fo.depth[i] - fs_.depth[i]) > 1e-4f * std::max(1.f, fo.depth[i])) ++depth_off;
    for (int c = 0; c < 3; ++c)
      if (std::abs(fo.rgb[i * 3 + c] - fs_.rgb[i * 3 + c]) > 1e-3f) ++colour_off;
  }
  INFO("pixels covered differently " << covered_differently << ", depth off " << depth_off << ", colour values off "
                                     << colour_off);
  CHECK(covered_differently == 0);
  CHECK(depth_off <= fo.depth.size() / 1000);
  CHECK(colour_off <= fo.rgb.size() / 1000);
  CHECK_THROWS_WITH(sim::subdivide(def, 0), Catch::Contains("at least 1"));
  test::require_no_validation_messages();
}

namespace {
sim::SimParams small_params(double blur) {
  sim::SimParams p;
  p.width = 96;
  p.height = 72;
  p.train_views = 1;
  p.novel_views = 0;
  p.blur_px = blur;
  p.seed = 3;
  return p;
}
}  // namespace

TEST_CASE("sim blur: zero shake gives blurry == sharp, sub-frame bound, blur scales with the parameter", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene scene = sim::make_default_scene();
  {
    sim::Simulator s(ctx, scene, small_params(0));
    events::EventSimulator ev(96, 72, events::EventModelParams::defaults(), 1);
    const auto r = s.simulate_view(0, ev);
    double diff = 0;
    for (size_t i = 0; i < r.blurry.size(); ++i)
      diff = std::max(diff, double(std::abs(r.blurry[i] - r.sharp_mid.rgb[i])));
    CHECK(diff < 1e-6);
    CHECK(r.mean_blur_px < 1e-3);
  }
  std::vector<double> measured;
  for (double blur : {3.0, 6.0, 12.0}) {
    sim::Simulator s(ctx, scene, small_params(blur));
    events::EventSimulator ev(96, 72, events::EventModelParams::defaults(), 1);
    double max_motion = 0;
    size_t intervals = 0;
    const auto r = s.simulate_view(0, ev, [&](const sim::Interval& iv) {
      for (size_t i = 0; i < iv.flow.size(); i += 2) {
        const double m = std::hypot(iv.flow[i], iv.flow[i + 1]);
        if (std::isfinite(m)) max_motion = std::max(max_motion, m);
      }
      ++intervals;
    });
    INFO("blur " << blur << ": " << intervals << " intervals, measured " << r.mean_blur_px << " px, max step "
                 << max_motion);
    CHECK(max_motion <= 0.5);
    CHECK(intervals + 1 == r.times.size());
    CHECK(intervals >= size_t(2 * blur));  // at least path / 0.5 px steps for the mean pixel
    CHECK(r.mean_blur_px == Approx(blur).epsilon(0.25));
    measured.push_back(r.mean_blur_px);
    std::printf("[sim] blur parameter %.0f px: measured mean blur %.2f px, %zu sub-frames, max step %.3f px\n", blur,
                r.mean_blur_px, r.times.size(), max_motion);
  }
  CHECK(measured[1] / measured[0] == Approx(2.0).epsilon(0.15));
  CHECK(measured[2] / measured[1] == Approx(2.0).epsilon(0.15));
  test::require_no_validation_messages();
}

TEST_CASE("sim flow: warping sub-frame k+1 by the ground-truth flow reproduces sub-frame k", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  // The default scene's geometry (depth variety, occlusions) with coarse random 4x4 textures, so
  // that bilinear resampling of the rendered frames is accurate at sub-pixel shifts (the default
  // textures have detail at the pixel scale, where any interpolation error exceeds the motion).
  sim::Scene scene = sim::make_default_scene();
  std::mt19937 g(5);
  for (auto& t : scene.textures) {
    t.width = t.height = 4;
    t.rgba.resize(16);
    for (auto& c : t.rgba) c = (g() & 0x00FFFFFFu) | 0xFF000000u;
  }
  // Drop the two posters (the last 4 triangles): their outlines are colour edges at the wall's depth.
  const size_t T = scene.triangle_count() - 4;
  scene.positions.resize(T * 9);
  scene.uvs.resize(T * 6);
  scene.material.resize(T);
  sim::Simulator s(ctx, scene, small_params(6));
  events::EventSimulator ev(96, 72, events::EventModelParams::defaults(), 1);
  const uint32_t W = 96, H = 72;
  double err_warp = 0, err_id = 0;
  size_t n = 0;
  s.simulate_view(0, ev, [&](const sim::Interval& iv) {
    // flow maps pixel x of frame k to x + flow in frame k+1: frame k ~ frame k+1 sampled there.
    const auto warped = sim::warp_by_flow(iv.b.rgb, W, H, 3, iv.flow);
    for (uint32_t y = 1; y + 1 < H; ++y)
      for (uint32_t x = 1; x + 1 < W; ++x) {
        const size_t p = size_t(y) * W + x;
        const float za = iv.a.depth[p];
        if (!(za > 0)) continue;
        // Non-occluded: every depth of frame k+1 around the target and of frame k around x agrees.
        const float tx = x + iv.flow[p * 2], ty = y + iv.flow[p * 2 + 1];
        bool ok = tx >= 1 && ty >= 1 && tx < W - 2 && ty < H - 2;
        for (int dy = -1; ok && dy <= 2; ++dy)
          for (int dx = -1; ok && dx <= 2; ++dx) {
            const float zb = iv.b.depth[size_t(int(ty) + dy) * W + size_t(int(tx) + dx)];
            if (!(std::abs(zb - za) < 0.02f * za)) ok = false;
          }
        if (!ok) continue;
        // Textured: a local gradient.
        const double g = std::abs(iv.a.rgb[(p + 1) * 3 + 1] - iv.a.rgb[(p - 1) * 3 + 1]) +
                         std::abs(iv.a.rgb[(p + W) * 3 + 1] - iv.a.rgb[(p - W) * 3 + 1]);
        if (g < 0.02 || g > 0.3) continue;  // textured, but not a hard (aliased) edge
        for (int c = 0; c < 3; ++c) {
          err_warp += std::abs(warped[p * 3 + c] - iv.a.rgb[p * 3 + c]);
          err_id += std::abs(iv.b.rgb[p * 3 + c] - iv.a.rgb[p * 3 + c]);
        }
        ++n;
      }
  });
  REQUIRE(n > 1000);
  std::printf("[sim] flow warp: mean abs error %.5f (warped) vs %.5f (unwarped) over %zu textured pixels\n",
              err_warp / (3 * n), err_id / (3 * n), n);
  CHECK(err_warp < 0.35 * err_id);
  test::require_no_validation_messages();
}

TEST_CASE("sim events: EDI with the known thresholds recovers the mid-exposure frame", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene scene = sim::make_default_scene();
  size_t exact_events = 0;
  for (int noisy = 0; noisy < 2; ++noisy) {
    sim::SimParams p = small_params(10);
    p.train_views = 2;
    p.events = noisy ? events::EventModelParams::defaults() : events::EventModelParams::ideal();
    sim::Simulator s(ctx, scene, p);
    double gain = 0, pb = 0, pe = 0, pe_maps = 0;
    size_t count = 0, dropped = 0;
    double th_mean = 0, th_var = 0, th_n = 0;
    for (int v = 0; v < p.train_views; ++v) {
      events::EventSimulator ev(p.width, p.height, p.events, p.seed + v);
      const auto r = s.simulate_view(v, ev);
      const EventStream es = ev.take_events();
      count += es.size();
      dropped += ev.refractory_dropped();
      events::EdiThresholds th;
      th.pos = p.events.theta_pos;
      th.neg = p.events.theta_neg;
      if (!noisy) {
        th.pos_map = ev.theta_pos_map();
        th.neg_map = ev.theta_neg_map();
      }
      const auto edi = events::edi_deblur(r.blurry.data(), 3, es, r.t0, r.t1, th);
      const double b = sim::psnr_srgb(r.blurry, r.sharp_mid.rgb), e = sim::psnr_srgb(edi, r.sharp_mid.rgb);
      pb += b / p.train_views;
      pe += e / p.train_views;
      gain += (e - b) / p.train_views;
      // The sensor's own per-pixel thresholds (what a calibrated EDI would use).
      events::EdiThresholds tm;
      tm.pos_map = ev.theta_pos_map();
      tm.neg_map = ev.theta_neg_map();
      pe_maps +=
          sim::psnr_srgb(events::edi_deblur(r.blurry.data(), 3, es, r.t0, r.t1, tm), r.sharp_mid.rgb) / p.train_views;
      for (const auto* m : {&tm.pos_map, &tm.neg_map})
        for (double x : *m) th_mean += x, th_var += x * x, th_n += 1;
    }
    th_mean /= th_n;
    const double th_sd = std::sqrt(th_var / th_n - th_mean * th_mean);
    std::printf(
        "[sim] EDI (%s events): PSNR %.2f dB vs blurry %.2f dB, gain %.2f dB; with the per-pixel thresholds %.2f dB; "
        "%zu events, %zu dropped by the refractory period, thresholds %.4f +- %.4f\n",
        noisy ? "default-noise" : "exact", pe, pb, gain, pe_maps, count, dropped, th_mean, th_sd);
    if (!noisy) {
      exact_events = count;
      CHECK(gain >= 6.0);
      CHECK(dropped == 0);
      CHECK(th_sd < 1e-6);
    } else {
      // The default sensor: per-pixel thresholds N(0.2, 0.03) ...
      const events::EventModelParams& m = p.events;
      CHECK(th_mean == Approx(m.theta_pos).margin(0.003));
      CHECK(th_sd == Approx(m.theta_sigma).epsilon(0.1));
      // ... cross E[theta / theta_i] ~ 1 + (sigma / theta)^2 times as often as exact ones; the
      // refractory period drops crossings (many, at edges moving 10 px) but still moves the
      // reference level past them, so emitted + dropped is that count.
      const double crossings = double(count + dropped),
                   expected = exact_events * (1 + std::pow(m.theta_sigma / m.theta_pos, 2));
      std::printf("[sim]   crossings %.0f, expected from the exact run %.0f\n", crossings, expected);
      CHECK(crossings == Approx(expected).epsilon(0.02));
      CHECK(dropped > count / 10);
      // EDI with the nominal thresholds still deblurs, if less (the dropped events are missing
      // from its double integral); the sensor's own thresholds do not do worse (the dropped
      // events, not the mismatch, cost the most here).
      CHECK(gain >= 2.0);
      CHECK(pe_maps > pe - 0.5);
    }
  }
  test::require_no_validation_messages();
}

TEST_CASE("sim dataset: the written dataset loads back", "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene scene = sim::make_default_scene();
  sim::SimParams p = small_params(4);
  p.width = 64;
  p.height = 48;
  p.train_views = 2;
  p.novel_views = 2;
  p.pose_noise_rot_deg = 0.5;
  p.pose_noise_trans = 0.01;
  sim::Simulator s(ctx, scene, p);
  sim::SimResult res = s.run();
  res.scene_source = scene.source;
  const fs::path dir = temp_dir("dataset");
  sim::write_simulation(res, dir);
  const io::Dataset d = io::load_dataset(dir);
  REQUIRE(d.layout == "evflow");
  REQUIRE(d.train.size() == 2);
  REQUIRE(d.novel.size() == 2);
  CHECK(d.events.size() == res.events.size());
  CHECK(d.events.size() > 1000);
  CHECK(d.train[1].exposure_start == Approx(res.train[1].t0));
  CHECK(d.train[1].exposure_end == Approx(res.train[1].t1));
  for (int k = 0; k < 9; ++k) CHECK(d.train[0].camera.R[k] == Approx(res.train[0].recorded_camera.R[k]).margin(1e-9));
  // Pose noise: the recorded pose differs from the ground truth, which is kept in gt/.
  double dr = 0;
  for (int k = 0; k < 9; ++k) dr += std::abs(res.train[0].recorded_camera.R[k] - res.train[0].gt_camera.R[k]);
  CHECK(dr > 1e-4);
  REQUIRE(d.train[0].sharp_mid.has_value());
  CHECK(d.train[0].blurry.width == 64);
  double diff = 0;
  for (size_t i = 0; i < d.train[0].blurry.data.size(); ++i)
    diff = std::max(diff, double(std::abs(io::linear_to_srgb(std::clamp(d.train[0].blurry.data[i], 0.f, 1.f)) -
                                          io::linear_to_srgb(std::clamp(res.train[0].blurry[i], 0.f, 1.f)))));
  CHECK(diff <= 0.6 / 255 + 1e-6);
  CHECK(d.manifest.contains("simulator"));
  CHECK(d.manifest["simulator"]["statistics"]["events"].get<size_t>() == res.events.size());
  CHECK(fs::exists(dir / "gt" / "trajectories.json"));
  CHECK(fs::exists(dir / "gt" / "depth" / "000.npy"));
  CHECK(fs::exists(dir / "gt" / "flow" / "000_mid.npy"));
  fs::remove_all(dir);
  test::require_no_validation_messages();
}

TEST_CASE("built-in scenes: the default room with other textures, the objects scene, unknown names refused", "[sim]") {
  const sim::Scene def = sim::make_builtin_scene("default");
  for (const char* name : {"gallery", "workshop"}) {
    const sim::Scene s = sim::make_builtin_scene(name);
    REQUIRE(s.source == name);
    REQUIRE(s.materials.size() == def.materials.size());
    REQUIRE(s.textures.size() == def.textures.size());
    int differ = 0;
    for (size_t i = 0; i < s.textures.size(); ++i) differ += s.textures[i].rgba != def.textures[i].rgba;
    CHECK(differ >= 5);  // most surfaces look different
  }
  // objects: textured boxes on surfaces without texture.
  const sim::Scene obj = sim::make_builtin_scene("objects");
  REQUIRE(obj.source == "objects");
  int plain = 0, textured = 0;
  for (const auto& m : obj.materials) (m.texture < 0 ? plain : textured)++;
  CHECK(plain >= 3);
  CHECK(textured >= 2);
  CHECK(sim::builtin_scene_blur_px("objects") == 8);
  REQUIRE(sim::builtin_scene_names() == std::vector<std::string>{"default", "gallery", "workshop", "objects"});
  REQUIRE_THROWS_WITH(sim::make_builtin_scene("atrium"), Catch::Contains("unknown built-in scene 'atrium'"));
}

TEST_CASE("sim shake: jerk adds a sudden change of velocity to the smooth shake, which it leaves as it was",
          "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene scene = sim::make_default_scene();
  sim::SimParams smooth_p = small_params(6), jerk_p = small_params(6);
  jerk_p.shake = "jerk";
  sim::Simulator smooth(ctx, scene, smooth_p), jerky(ctx, scene, jerk_p);
  // The largest second difference of the camera's rotation over the exposure, per sample step^2.
  auto max_acceleration = [](const sim::Simulator& s) {
    const int n = 400;
    double best = 0;
    for (int i = 1; i < n; ++i) {
      const Camera a = s.shake_pose(0, double(i - 1) / n, 1.0), b = s.shake_pose(0, double(i) / n, 1.0),
                   c = s.shake_pose(0, double(i + 1) / n, 1.0);
      for (int k = 0; k < 9; ++k) best = std::max(best, std::abs(a.R[k] - 2 * b.R[k] + c.R[k]) * n * n);
    }
    return best;
  };
  const double acc_smooth = max_acceleration(smooth), acc_jerk = max_acceleration(jerky);
  INFO("largest rotation acceleration: smooth " << acc_smooth << ", jerk " << acc_jerk);
  CHECK(acc_jerk > 3 * acc_smooth);
  // Both keep the ground-truth pose at mid-exposure.
  const Camera m0 = smooth.shake_pose(0, 0.5, 1.0), m1 = jerky.shake_pose(0, 0.5, 1.0);
  for (int k = 0; k < 9; ++k) CHECK(m0.R[k] == m1.R[k]);
  sim::SimParams bad = small_params(6);
  bad.shake = "wobble";
  REQUIRE_THROWS_WITH(sim::Simulator(ctx, scene, bad), Catch::Contains("smooth or jerk"));
  test::require_no_validation_messages();
}
