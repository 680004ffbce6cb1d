#include "sim/scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <stdexcept>

#include <tiny_gltf.h>

#include "io/image.h"

namespace evflow::sim {

namespace fs = std::filesystem;

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

// ---------------------------------------------------------------------------------------------
// glTF reading

namespace {

using Mat4 = std::array<double, 16>;  // column-major, like glTF

Mat4 identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }
Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + rr] * b[c * 4 + k];
      r[c * 4 + rr] = s;
    }
  return r;
}

Mat4 node_matrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    Mat4 m;
    for (int i = 0; i < 16; ++i) m[i] = n.matrix[i];
    return m;
  }
  Mat4 T = identity(), R = identity(), S = identity();
  if (n.translation.size() == 3) { T[12] = n.translation[0]; T[13] = n.translation[1]; T[14] = n.translation[2]; }
  if (n.rotation.size() == 4) {
    const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    R = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w), 0,
         2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w), 0,
         2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y), 0,
         0, 0, 0, 1};
  }
  if (n.scale.size() == 3) { S[0] = n.scale[0]; S[5] = n.scale[1]; S[10] = n.scale[2]; }
  return mul(T, mul(R, S));
}

struct Reader {
  const tinygltf::Model& m;
  std::string file;

  [[noreturn]] void fail(const std::string& what) const { throw std::runtime_error(file + ": " + what); }

  // Reads accessor `index` as floats (count x comps); normalised integer types are converted.
  std::vector<float> floats(int index, int comps, const char* what) const {
    if (index < 0 || index >= int(m.accessors.size())) fail(std::string(what) + " accessor index out of range");
    const auto& a = m.accessors[index];
    if (a.sparse.isSparse) fail(std::string(what) + ": sparse accessors are not supported");
    const int nc = tinygltf::GetNumComponentsInType(a.type);
    if (nc != comps) fail(std::string(what) + ": expected " + std::to_string(comps) + " components, got " + std::to_string(nc));
    std::vector<float> out(a.count * comps, 0.f);
    if (a.bufferView < 0) return out;  // all zeros (glTF: no bufferView = zeros)
    const uint8_t* base = data(a, what);
    const int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
    const size_t stride = stride_of(a, nc * csize);
    for (size_t i = 0; i < a.count; ++i)
      for (int c = 0; c < comps; ++c) {
        const uint8_t* p = base + i * stride + c * csize;
        float v;
        switch (a.componentType) {
          case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, p, 4); break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *p / 255.f; break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); v = u / 65535.f; break; }
          case TINYGLTF_COMPONENT_TYPE_BYTE: v = std::max(int8_t(*p) / 127.f, -1.f); break;
          case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t s; std::memcpy(&s, p, 2); v = std::max(s / 32767.f, -1.f); break; }
          default: fail(std::string(what) + ": unsupported component type " + std::to_string(a.componentType));
        }
        out[i * comps + c] = v;
      }
    return out;
  }

  std::vector<uint32_t> indices(int index) const {
    if (index < 0 || index >= int(m.accessors.size())) fail("index accessor out of range");
    const auto& a = m.accessors[index];
    if (a.sparse.isSparse || a.bufferView < 0) fail("indices: sparse or bufferless accessors are not supported");
    if (a.type != TINYGLTF_TYPE_SCALAR) fail("indices: accessor is not SCALAR");
    const uint8_t* base = data(a, "indices");
    const int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
    const size_t stride = stride_of(a, csize);
    std::vector<uint32_t> out(a.count);
    for (size_t i = 0; i < a.count; ++i) {
      const uint8_t* p = base + i * stride;
      switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[i] = *p; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t u; std::memcpy(&u, p, 2); out[i] = u; break; }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: std::memcpy(&out[i], p, 4); break;
        default: fail("indices: unsupported component type " + std::to_string(a.componentType));
      }
    }
    return out;
  }

  size_t stride_of(const tinygltf::Accessor& a, size_t packed) const {
    const auto& bv = m.bufferViews[a.bufferView];
    return bv.byteStride ? bv.byteStride : packed;
  }

  const uint8_t* data(const tinygltf::Accessor& a, const char* what) const {
    if (a.bufferView >= int(m.bufferViews.size())) fail(std::string(what) + ": bufferView index out of range");
    const auto& bv = m.bufferViews[a.bufferView];
    if (bv.buffer < 0 || bv.buffer >= int(m.buffers.size())) fail(std::string(what) + ": buffer index out of range");
    const auto& buf = m.buffers[bv.buffer].data;
    const int nc = tinygltf::GetNumComponentsInType(a.type);
    const int csize = tinygltf::GetComponentSizeInBytes(a.componentType);
    if (nc <= 0 || csize <= 0) fail(std::string(what) + ": invalid accessor type");
    const size_t stride = bv.byteStride ? bv.byteStride : size_t(nc) * csize;
    const size_t need = a.count ? a.byteOffset + (a.count - 1) * stride + size_t(nc) * csize : 0;
    if (bv.byteOffset + need > buf.size() || need > bv.byteLength)
      fail(std::string(what) + ": accessor reads past the end of its buffer (truncated file?)");
    return buf.data() + bv.byteOffset + a.byteOffset;
  }
};

uint32_t wrap_mode(int gl) {
  if (gl == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return Texture::Clamp;
  if (gl == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return Texture::Mirror;
  return Texture::Repeat;
}

}  // namespace

Scene load_gltf(const fs::path& path) {
  const std::string file = path.string();
  if (!fs::exists(path)) throw std::runtime_error(file + ": no such file");
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  bool ok = false;
  try {
    ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, file) : loader.LoadASCIIFromFile(&model, &err, &warn, file);
  } catch (const std::exception& e) {
    throw std::runtime_error(file + ": malformed glTF: " + e.what());
  }
  if (!ok) throw std::runtime_error(file + ": cannot read glTF: " + (err.empty() ? std::string("unknown error") : err));
  Reader rd{model, file};
  Scene s;
  s.source = file;

  // Textures: one per glTF texture (base-colour images are sRGB-encoded, kept as they are).
  std::vector<int> tex_map(model.textures.size(), -1);
  auto get_texture = [&](int ti) -> int {
    if (ti < 0 || ti >= int(model.textures.size())) rd.fail("texture index " + std::to_string(ti) + " out of range");
    if (tex_map[ti] >= 0) return tex_map[ti];
    const auto& t = model.textures[ti];
    if (t.source < 0 || t.source >= int(model.images.size())) rd.fail("texture " + std::to_string(ti) + " has no image");
    const auto& img = model.images[t.source];
    if (img.width <= 0 || img.height <= 0 || img.image.empty())
      rd.fail("image " + std::to_string(t.source) + " ('" + img.uri + "') could not be decoded");
    const int comp = img.component, bytes = img.bits == 16 ? 2 : 1;
    if (comp < 1 || comp > 4 || img.image.size() < size_t(img.width) * img.height * comp * bytes)
      rd.fail("image " + std::to_string(t.source) + " has an unsupported pixel layout");
    Texture tx;
    tx.name = img.name.empty() ? img.uri : img.name;
    tx.width = img.width;
    tx.height = img.height;
    tx.rgba.resize(size_t(img.width) * img.height);
    for (size_t i = 0; i < tx.rgba.size(); ++i) {
      uint32_t ch[4] = {0, 0, 0, 255};
      for (int c = 0; c < comp; ++c) {
        const size_t o = (i * comp + c) * bytes;
        ch[c] = bytes == 2 ? img.image[o + 1] : img.image[o];  // little-endian 16-bit: high byte
      }
      if (comp <= 2) { ch[3] = comp == 2 ? ch[1] : 255; ch[1] = ch[2] = ch[0]; }
      tx.rgba[i] = ch[0] | ch[1] << 8 | ch[2] << 16 | ch[3] << 24;
    }
    if (t.sampler >= 0 && t.sampler < int(model.samplers.size())) {
      tx.wrap_s = wrap_mode(model.samplers[t.sampler].wrapS);
      tx.wrap_t = wrap_mode(model.samplers[t.sampler].wrapT);
    }
    s.textures.push_back(std::move(tx));
    return tex_map[ti] = int(s.textures.size()) - 1;
  };
  for (const auto& gm : model.materials) {
    Material mt;
    mt.name = gm.name;
    const auto& pbr = gm.pbrMetallicRoughness;
    for (int c = 0; c < 4 && c < int(pbr.baseColorFactor.size()); ++c) mt.base_color[c] = float(pbr.baseColorFactor[c]);
    if (pbr.baseColorTexture.index >= 0) {
      if (pbr.baseColorTexture.texCoord != 0) rd.fail("material '" + gm.name + "': only TEXCOORD_0 is supported");
      mt.texture = get_texture(pbr.baseColorTexture.index);
    }
    s.materials.push_back(mt);
  }
  const uint32_t default_material = uint32_t(s.materials.size());
  bool used_default = false;

  std::function<void(int, const Mat4&, int)> visit = [&](int ni, const Mat4& parent, int depth) {
    if (ni < 0 || ni >= int(model.nodes.size())) rd.fail("node index " + std::to_string(ni) + " out of range");
    if (depth > 256) rd.fail("node hierarchy too deep (cycle?)");
    const auto& node = model.nodes[ni];
    const Mat4 M = mul(parent, node_matrix(node));
    if (node.mesh >= 0) {
      if (node.mesh >= int(model.meshes.size())) rd.fail("mesh index out of range");
      for (const auto& prim : model.meshes[node.mesh].primitives) {
        if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) continue;  // points/lines: skipped
        auto pit = prim.attributes.find("POSITION");
        if (pit == prim.attributes.end()) rd.fail("primitive without POSITION");
        std::vector<float> pos = rd.floats(pit->second, 3, "POSITION");
        const size_t nv = pos.size() / 3;
        std::vector<float> uv(nv * 2, 0.f);
        auto uit = prim.attributes.find("TEXCOORD_0");
        if (uit != prim.attributes.end()) {
          uv = rd.floats(uit->second, 2, "TEXCOORD_0");
          if (uv.size() != nv * 2) rd.fail("TEXCOORD_0 count differs from POSITION count");
        }
        std::vector<uint32_t> idx;
        if (prim.indices >= 0) idx = rd.indices(prim.indices);
        else { idx.resize(nv); for (size_t i = 0; i < nv; ++i) idx[i] = uint32_t(i); }
        if (idx.size() % 3) rd.fail("triangle primitive with " + std::to_string(idx.size()) + " indices (not a multiple of 3)");
        uint32_t mat = default_material;
        if (prim.material >= 0) {
          if (prim.material >= int(s.materials.size())) rd.fail("material index out of range");
          mat = uint32_t(prim.material);
        } else used_default = true;
        for (size_t k = 0; k < idx.size(); k += 3) {
          for (int j = 0; j < 3; ++j) {
            const uint32_t v = idx[k + j];
            if (v >= nv) rd.fail("vertex index " + std::to_string(v) + " out of range");
            const double x = pos[v * 3], y = pos[v * 3 + 1], z = pos[v * 3 + 2];
            for (int c = 0; c < 3; ++c) s.positions.push_back(float(M[c] * x + M[4 + c] * y + M[8 + c] * z + M[12 + c]));
            s.uvs.push_back(uv[v * 2]);
            s.uvs.push_back(uv[v * 2 + 1]);
          }
          s.material.push_back(mat);
        }
      }
    }
    for (int c : node.children) visit(c, M, depth + 1);
  };
  if (model.defaultScene >= 0 && model.defaultScene < int(model.scenes.size())) {
    for (int n : model.scenes[model.defaultScene].nodes) visit(n, identity(), 0);
  } else if (!model.scenes.empty()) {
    for (int n : model.scenes[0].nodes) visit(n, identity(), 0);
  } else {
    std::vector<bool> child(model.nodes.size(), false);
    for (auto& n : model.nodes)
      for (int c : n.children)
        if (c >= 0 && c < int(child.size())) child[c] = true;
    for (size_t i = 0; i < model.nodes.size(); ++i)
      if (!child[i]) visit(int(i), identity(), 0);
  }
  if (used_default) s.materials.push_back(Material{"default", {1, 1, 1, 1}, -1});
  if (s.triangle_count() == 0) rd.fail("the scene has no triangles");
  s.validate();
  return s;
}

// ---------------------------------------------------------------------------------------------
// glTF writing

void write_gltf(const Scene& scene, const fs::path& path) {
  scene.validate();
  tinygltf::Model m;
  m.asset.version = "2.0";
  m.asset.generator = "evflow simulate";
  tinygltf::Buffer buf;
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const auto& t = scene.textures[i];
    tinygltf::Image img;
    img.name = t.name;
    img.width = int(t.width);
    img.height = int(t.height);
    img.component = 4;
    img.bits = 8;
    img.pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    img.mimeType = "image/png";
    img.image.resize(t.rgba.size() * 4);
    std::memcpy(img.image.data(), t.rgba.data(), img.image.size());
    m.images.push_back(img);
    tinygltf::Sampler smp;
    auto gl_wrap = [](uint32_t w) {
      return w == Texture::Clamp ? TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE
                                 : w == Texture::Mirror ? TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT : TINYGLTF_TEXTURE_WRAP_REPEAT;
    };
    smp.wrapS = gl_wrap(t.wrap_s);
    smp.wrapT = gl_wrap(t.wrap_t);
    smp.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    smp.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
    m.samplers.push_back(smp);
    tinygltf::Texture tx;
    tx.source = int(i);
    tx.sampler = int(i);
    m.textures.push_back(tx);
  }
  for (const auto& mt : scene.materials) {
    tinygltf::Material gm;
    gm.name = mt.name;
    gm.pbrMetallicRoughness.baseColorFactor = {mt.base_color[0], mt.base_color[1], mt.base_color[2], mt.base_color[3]};
    gm.pbrMetallicRoughness.baseColorTexture.index = mt.texture;
    gm.pbrMetallicRoughness.metallicFactor = 0;
    gm.pbrMetallicRoughness.roughnessFactor = 1;
    gm.doubleSided = true;
    m.materials.push_back(gm);
  }
  tinygltf::Mesh mesh;
  auto append = [&](const void* p, size_t bytes) {
    const size_t off = buf.data.size();
    buf.data.resize(off + ((bytes + 3) & ~size_t(3)), 0);
    std::memcpy(buf.data.data() + off, p, bytes);
    return off;
  };
  for (uint32_t mi = 0; mi < scene.materials.size(); ++mi) {
    std::vector<float> pos, uv;
    for (size_t t = 0; t < scene.triangle_count(); ++t)
      if (scene.material[t] == mi) {
        pos.insert(pos.end(), scene.positions.begin() + t * 9, scene.positions.begin() + t * 9 + 9);
        uv.insert(uv.end(), scene.uvs.begin() + t * 6, scene.uvs.begin() + t * 6 + 6);
      }
    if (pos.empty()) continue;
    const size_t nv = pos.size() / 3;
    std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < pos.size(); ++i) { lo[i % 3] = std::min(lo[i % 3], double(pos[i])); hi[i % 3] = std::max(hi[i % 3], double(pos[i])); }
    auto add_view = [&](const std::vector<float>& v, int type, bool minmax) {
      tinygltf::BufferView bv;
      bv.buffer = 0;
      bv.byteOffset = append(v.data(), v.size() * 4);
      bv.byteLength = v.size() * 4;
      bv.target = TINYGLTF_TARGET_ARRAY_BUFFER;
      m.bufferViews.push_back(bv);
      tinygltf::Accessor a;
      a.bufferView = int(m.bufferViews.size()) - 1;
      a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
      a.count = nv;
      a.type = type;
      if (minmax) { a.minValues = {lo[0], lo[1], lo[2]}; a.maxValues = {hi[0], hi[1], hi[2]}; }
      m.accessors.push_back(a);
      return int(m.accessors.size()) - 1;
    };
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = add_view(pos, TINYGLTF_TYPE_VEC3, true);
    prim.attributes["TEXCOORD_0"] = add_view(uv, TINYGLTF_TYPE_VEC2, false);
    prim.material = int(mi);
    mesh.primitives.push_back(prim);
  }
  m.buffers.push_back(buf);
  m.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  m.nodes.push_back(node);
  tinygltf::Scene sc;
  sc.nodes = {0};
  m.scenes.push_back(sc);
  m.defaultScene = 0;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  tinygltf::TinyGLTF w;
  if (!w.WriteGltfSceneToFile(&m, path.string(), true, true, ext != ".glb", ext == ".glb"))
    throw std::runtime_error(path.string() + ": cannot write glTF");
}

// ---------------------------------------------------------------------------------------------
// The default scene

namespace {

struct Rng {
  uint64_t s;
  uint64_t next() { s += 0x9E3779B97F4A7C15ull; uint64_t z = s; z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull; z = (z ^ (z >> 27)) * 0x94D049BB133111EBull; return z ^ (z >> 31); }
  double uni() { return (next() >> 11) * (1.0 / 9007199254740992.0); }
};

uint32_t hash2(int x, int y, uint32_t seed) {
  uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
  return h;
}
// Smooth value noise in [0, 1] with period `period` cells.
double value_noise(double x, double y, uint32_t seed, int period) {
  const int xi = int(std::floor(x)), yi = int(std::floor(y));
  const double fx = x - xi, fy = y - yi;
  auto v = [&](int a, int b) { return (hash2(((a % period) + period) % period, ((b % period) + period) % period, seed) & 0xFFFF) / 65535.0; };
  const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
  return (v(xi, yi) * (1 - sx) + v(xi + 1, yi) * sx) * (1 - sy) + (v(xi, yi + 1) * (1 - sx) + v(xi + 1, yi + 1) * sx) * sy;
}
double fbm(double u, double v, uint32_t seed, int base_period) {
  double s = 0, a = 0.5;
  int p = base_period;
  for (int o = 0; o < 4; ++o, a *= 0.5, p *= 2) s += a * value_noise(u * p, v * p, seed + o, p);
  return s / 0.9375;
}

struct LinearTex {
  uint32_t w, h;
  std::vector<float> rgb;
  LinearTex(uint32_t W, uint32_t H) : w(W), h(H), rgb(size_t(W) * H * 3) {}
  void set(uint32_t x, uint32_t y, double r, double g, double b) {
    float* p = &rgb[(size_t(y) * w + x) * 3];
    p[0] = float(r); p[1] = float(g); p[2] = float(b);
  }
  Texture encode(const std::string& name) const {
    Texture t;
    t.name = name;
    t.width = w;
    t.height = h;
    t.rgba.resize(size_t(w) * h);
    for (size_t i = 0; i < t.rgba.size(); ++i) {
      uint32_t c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = uint32_t(std::lround(std::clamp(io::linear_to_srgb(std::clamp(rgb[i * 3 + k], 0.f, 1.f)), 0.f, 1.f) * 255.f));
      t.rgba[i] = c[0] | c[1] << 8 | c[2] << 16 | 0xFF000000u;
    }
    return t;
  }
};

// Paper with rows of glyph-like strokes (text): 5x7 cells of random bars, a large headline row.
Texture text_texture(uint32_t seed, double paper, double ink, const std::array<double, 3>& tint) {
  const uint32_t N = 512;
  LinearTex t(N, N);
  std::vector<uint8_t> mask(size_t(N) * N, 0);
  Rng rng{seed};
  auto glyph = [&](int x0, int y0, int scale) {
    // A glyph: a few strokes on a 5x7 grid.
    const int strokes = 2 + int(rng.uni() * 3);
    for (int s = 0; s < strokes; ++s) {
      const bool horiz = rng.uni() < 0.5;
      const int a = int(rng.uni() * (horiz ? 7 : 5)), b0 = int(rng.uni() * 3), len = 2 + int(rng.uni() * (horiz ? 3 : 5));
      for (int k = 0; k < len; ++k) {
        const int gx = horiz ? b0 + k : a, gy = horiz ? a : b0 + k;
        if (gx >= 5 || gy >= 7) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int x = x0 + gx * scale + dx, y = y0 + gy * scale + dy;
            if (x >= 0 && y >= 0 && x < int(N) && y < int(N)) mask[size_t(y) * N + x] = 1;
          }
      }
    }
  };
  int y = 16;
  // Headline.
  for (int x = 24; x + 30 < int(N) - 24; x += 36) glyph(x, y, 5);
  y += 56;
  while (y + 16 < int(N) - 16) {
    int x = 24;
    while (x + 12 < int(N) - 24) {
      const int word = 2 + int(rng.uni() * 6);
      for (int k = 0; k < word && x + 12 < int(N) - 24; ++k, x += 14) glyph(x, y, 2);
      x += 12;
    }
    y += rng.uni() < 0.15 ? 34 : 20;
  }
  for (uint32_t yy = 0; yy < N; ++yy)
    for (uint32_t xx = 0; xx < N; ++xx) {
      const double grain = 0.9 + 0.1 * fbm(xx / double(N), yy / double(N), seed + 7, 8);
      const double v = (mask[size_t(yy) * N + xx] ? ink : paper) * grain;
      t.set(xx, yy, v * tint[0], v * tint[1], v * tint[2]);
    }
  return t.encode("text" + std::to_string(seed));
}

Texture checker_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const int cx = x / 64, cy = y / 64;
      const double n = fbm(x / double(N), y / double(N), 11, 8);
      const bool dark = (cx + cy) & 1;
      double r = dark ? 0.06 : 0.55, g = dark ? 0.05 : 0.45, b = dark ? 0.04 : 0.3;
      const double k = 0.7 + 0.6 * n;
      // Fine wood-grain lines.
      const double grain = 0.85 + 0.15 * std::sin((y + 6 * n * 64) * 0.9);
      if (x % 64 == 0 || y % 64 == 0) r = g = b = 0.02;
      t.set(x, y, r * k * grain, g * k * grain, b * k * grain);
    }
  return t.encode("floor");
}

Texture brick_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const int row = y / 32, shift = (row & 1) * 32;
      const int col = (x + shift) / 64;
      const bool mortar = (y % 32) < 3 || ((x + shift) % 64) < 3;
      const uint32_t h = hash2(col, row, 5);
      const double base = 0.35 + 0.3 * ((h & 0xFF) / 255.0);
      const double n = 0.75 + 0.5 * fbm(x / double(N), y / double(N), 3, 16);
      if (mortar) t.set(x, y, 0.8, 0.78, 0.72);
      else t.set(x, y, base * n, 0.35 * base * n, 0.25 * base * n);
    }
  return t.encode("brick");
}

Texture noise_texture(uint32_t seed) {
  const uint32_t N = 256;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double u = x / double(N), v = y / double(N);
      const double a = fbm(u, v, seed, 4), b = fbm(u, v, seed + 100, 4), c = fbm(u, v, seed + 200, 8);
      const double spots = c > 0.62 ? 0.05 : 1.0;
      t.set(x, y, std::pow(a, 2.0) * spots, std::pow(b, 2.0) * spots * 0.9, 0.6 * c * c * spots);
    }
  return t.encode("noise" + std::to_string(seed));
}

Texture grating_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double u = x / double(N) - 0.5, v = y / double(N) - 0.5;
      const double r = std::sqrt(u * u + v * v);
      const double s = 0.5 + 0.5 * std::sin(2 * M_PI * (14 * r + 40 * r * r));
      const double band = (x / 128 + y / 128) & 1 ? 1.0 : 0.55;
      t.set(x, y, (0.03 + 0.9 * s) * band, (0.03 + 0.85 * s) * band, (0.05 + 0.7 * s));
    }
  return t.encode("grating");
}

Texture dark_texture() {
  const uint32_t N = 256;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double n = fbm(x / double(N), y / double(N), 21, 8);
      const bool weave = ((x / 4) + (y / 4)) & 1;
      const double v = 0.012 + 0.03 * n + (weave ? 0.01 : 0.0);
      t.set(x, y, v, v * 0.95, v * 1.2);
    }
  return t.encode("dark");
}

}  // namespace

namespace {

// The room of the built-in scenes; `textures` fills its seven material slots: back-wall poster,
// floor, right wall, noise boxes, grating, dark (left wall and a box), sign.
Scene make_room(const std::string& source, std::vector<Texture> textures) {
  Scene s;
  s.source = source;
  s.textures = std::move(textures);
  auto mat = [&](const char* name, int tex, std::array<float, 4> f = {1, 1, 1, 1}) {
    s.materials.push_back(Material{name, f, tex});
    return uint32_t(s.materials.size() - 1);
  };
  const uint32_t m_text = mat("poster", 0), m_floor = mat("floor", 1), m_brick = mat("brick", 2), m_noise = mat("noise", 3),
                 m_grating = mat("grating", 4), m_dark = mat("dark", 5), m_sign = mat("sign", 6),
                 m_white = mat("white", 0, {1.1f, 1.1f, 1.1f, 1});
  // Room: floor, back wall, left (dark) and right (brick) walls; open top and front.
  s.add_quad({-4, -1, 3}, {4, -1, 3}, {4, -1, -4}, {-4, -1, -4}, m_floor, 4, 3.5f);
  s.add_quad({-4, -1, -4}, {4, -1, -4}, {4, 3, -4}, {-4, 3, -4}, m_text, 2, 1);
  s.add_quad({-4, -1, 3}, {-4, -1, -4}, {-4, 3, -4}, {-4, 3, 3}, m_dark, 3.5f, 2);
  s.add_quad({4, -1, -4}, {4, -1, 3}, {4, 3, 3}, {4, 3, -4}, m_brick, 3.5f, 2);
  // Objects at several depths.
  s.add_box({-2.4f, -1, -2.8f}, {-1.0f, 0.5f, -1.6f}, m_noise, 0.7f);
  s.add_box({0.6f, -1, -3.2f}, {2.3f, 1.3f, -2.4f}, m_white, 0.5f);
  s.add_box({-0.5f, -1, -0.6f}, {0.5f, -0.25f, 0.3f}, m_grating, 1.0f);
  s.add_box({2.0f, -1, -0.8f}, {2.9f, 0.1f, 0.2f}, m_dark, 1.0f);
  s.add_box({-1.8f, -1, 0.6f}, {-1.2f, -0.6f, 1.2f}, m_noise, 1.5f);
  // Posters: a grating on the left wall, a bright-on-dark sign above the white box.
  s.add_quad({-3.98f, -0.2f, -2.5f}, {-3.98f, -0.2f, -0.5f}, {-3.98f, 1.6f, -0.5f}, {-3.98f, 1.6f, -2.5f}, m_grating);
  s.add_quad({0.4f, 1.6f, -3.97f}, {2.6f, 1.6f, -3.97f}, {2.6f, 2.6f, -3.97f}, {0.4f, 2.6f, -3.97f}, m_sign, 1, 0.45f);
  s.has_view_hint = true;
  s.view_target = {0, 0, -1.5f};
  s.view_radius = 5.0f;
  s.view_height = 1.0f;
  s.validate();
  return s;
}

}  // namespace

Scene make_default_scene() {
  return make_room("default", {text_texture(1, 0.85, 0.03, {1.0, 0.97, 0.9}), checker_texture(), brick_texture(),
                               noise_texture(3), grating_texture(), dark_texture(), text_texture(2, 0.04, 0.9, {1.0, 0.85, 0.5})});
}

std::vector<std::string> builtin_scene_names() { return {"default", "gallery", "workshop"}; }

Scene make_builtin_scene(const std::string& name) {
  if (name == "default") return make_default_scene();
  // Same room, other surfaces: fine print everywhere and bright noise (high-frequency texture).
  if (name == "gallery")
    return make_room("gallery", {text_texture(11, 0.9, 0.05, {0.95, 0.95, 1.0}), noise_texture(17), text_texture(12, 0.1, 0.95, {0.7, 1.0, 0.8}),
                                 brick_texture(), text_texture(13, 0.8, 0.1, {1.0, 0.9, 0.8}), noise_texture(23), grating_texture()});
  // Same room, other surfaces: large smooth shapes, coarse bricks and gratings, dark corners.
  if (name == "workshop")
    return make_room("workshop", {brick_texture(), grating_texture(), checker_texture(), dark_texture(), checker_texture(),
                                  brick_texture(), noise_texture(31)});
  throw std::invalid_argument("unknown built-in scene '" + name + "' (default, gallery, workshop)");
}

}  // namespace evflow::sim
