#include "sim/gltf_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <tiny_gltf.h>

#include "io/atomic_file.h"

namespace evflow::sim {

namespace fs = std::filesystem;

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
  if (n.translation.size() == 3) {
    T[12] = n.translation[0];
    T[13] = n.translation[1];
    T[14] = n.translation[2];
  }
  if (n.rotation.size() == 4) {
    const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    R = {1 - 2 * (y * y + z * z),
         2 * (x * y + z * w),
         2 * (x * z - y * w),
         0,
         2 * (x * y - z * w),
         1 - 2 * (x * x + z * z),
         2 * (y * z + x * w),
         0,
         2 * (x * z + y * w),
         2 * (y * z - x * w),
         1 - 2 * (x * x + y * y),
         0,
         0,
         0,
         0,
         1};
  }
  if (n.scale.size() == 3) {
    S[0] = n.scale[0];
    S[5] = n.scale[1];
    S[10] = n.scale[2];
  }
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
    if (nc != comps)
      fail(std::string(what) + ": expected " + std::to_string(comps) + " components, got " + std::to_string(nc));
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
          case TINYGLTF_COMPONENT_TYPE_FLOAT:
            std::memcpy(&v, p, 4);
            break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            v = *p / 255.f;
            break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t u;
            std::memcpy(&u, p, 2);
            v = u / 65535.f;
            break;
          }
          case TINYGLTF_COMPONENT_TYPE_BYTE:
            v = std::max(int8_t(*p) / 127.f, -1.f);
            break;
          case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t s;
            std::memcpy(&s, p, 2);
            v = std::max(s / 32767.f, -1.f);
            break;
          }
          default:
            fail(std::string(what) + ": unsupported component type " + std::to_string(a.componentType));
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
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          out[i] = *p;
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          uint16_t u;
          std::memcpy(&u, p, 2);
          out[i] = u;
          break;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
          std::memcpy(&out[i], p, 4);
          break;
        default:
          fail("indices: unsupported component type " + std::to_string(a.componentType));
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

tinygltf::Model read_model(const fs::path& path) {
  const std::string file = path.string();
  if (!fs::exists(path)) throw std::runtime_error(file + ": no such file");
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  bool ok = false;
  try {
    ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model, &err, &warn, file)
                       : loader.LoadASCIIFromFile(&model, &err, &warn, file);
  } catch (const std::exception& e) { throw std::runtime_error(file + ": malformed glTF: " + e.what()); }
  if (!ok) throw std::runtime_error(file + ": cannot read glTF: " + (err.empty() ? std::string("unknown error") : err));
  return model;
}

// glTF texture `ti` as an RGBA8 texture (base-colour images are sRGB-encoded, kept as they are).
Texture decode_texture(const Reader& rd, int ti) {
  const tinygltf::Model& model = rd.m;
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
    if (comp <= 2) {
      ch[3] = comp == 2 ? ch[1] : 255;
      ch[1] = ch[2] = ch[0];
    }
    tx.rgba[i] = ch[0] | ch[1] << 8 | ch[2] << 16 | ch[3] << 24;
  }
  if (t.sampler >= 0 && t.sampler < int(model.samplers.size())) {
    tx.wrap_s = wrap_mode(model.samplers[t.sampler].wrapS);
    tx.wrap_t = wrap_mode(model.samplers[t.sampler].wrapT);
  }
  return tx;
}

// Fills a Scene from a glTF model: textures (one per glTF texture used), materials, and the
// triangles of every node reached from the scene's roots.
struct SceneBuilder {
  const Reader& rd;
  Scene& s;
  std::vector<int> tex_map;
  uint32_t default_material = 0;
  bool used_default = false;

  int texture(int ti) {
    if (ti < 0 || ti >= int(rd.m.textures.size())) rd.fail("texture index " + std::to_string(ti) + " out of range");
    if (tex_map[ti] >= 0) return tex_map[ti];
    s.textures.push_back(decode_texture(rd, ti));
    return tex_map[ti] = int(s.textures.size()) - 1;
  }

  void materials() {
    tex_map.assign(rd.m.textures.size(), -1);
    for (const auto& gm : rd.m.materials) {
      Material mt;
      mt.name = gm.name;
      const auto& pbr = gm.pbrMetallicRoughness;
      for (int c = 0; c < 4 && c < int(pbr.baseColorFactor.size()); ++c)
        mt.base_color[c] = float(pbr.baseColorFactor[c]);
      if (pbr.baseColorTexture.index >= 0) {
        if (pbr.baseColorTexture.texCoord != 0) rd.fail("material '" + gm.name + "': only TEXCOORD_0 is supported");
        mt.texture = texture(pbr.baseColorTexture.index);
      }
      s.materials.push_back(mt);
    }
    default_material = uint32_t(s.materials.size());
  }

  void primitive(const tinygltf::Primitive& prim, const Mat4& M) {
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) return;  // points/lines: skipped
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
    if (prim.indices >= 0)
      idx = rd.indices(prim.indices);
    else {
      idx.resize(nv);
      for (size_t i = 0; i < nv; ++i) idx[i] = uint32_t(i);
    }
    if (idx.size() % 3)
      rd.fail("triangle primitive with " + std::to_string(idx.size()) + " indices (not a multiple of 3)");
    uint32_t mat = default_material;
    if (prim.material >= 0) {
      if (prim.material >= int(s.materials.size())) rd.fail("material index out of range");
      mat = uint32_t(prim.material);
    } else
      used_default = true;
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

  void visit(int ni, const Mat4& parent, int depth) {
    const tinygltf::Model& model = rd.m;
    if (ni < 0 || ni >= int(model.nodes.size())) rd.fail("node index " + std::to_string(ni) + " out of range");
    if (depth > 256) rd.fail("node hierarchy too deep (cycle?)");
    const auto& node = model.nodes[ni];
    const Mat4 M = mul(parent, node_matrix(node));
    if (node.mesh >= 0) {
      if (node.mesh >= int(model.meshes.size())) rd.fail("mesh index out of range");
      for (const auto& prim : model.meshes[node.mesh].primitives) primitive(prim, M);
    }
    for (int c : node.children) visit(c, M, depth + 1);
  }

  // The default scene's root nodes, else the first scene's, else every node that is no child.
  void visit_roots() {
    const tinygltf::Model& model = rd.m;
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
  }
};

// ---------------------------------------------------------------------------------------------
// glTF writing

int gl_wrap(uint32_t w) {
  return w == Texture::Clamp    ? TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE
         : w == Texture::Mirror ? TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT
                                : TINYGLTF_TEXTURE_WRAP_REPEAT;
}

// One PNG image, sampler and texture per scene texture (same indices).
void add_textures(tinygltf::Model& m, const Scene& scene) {
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
}

void add_materials(tinygltf::Model& m, const Scene& scene) {
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
}

// Appends the float array `v` (`nv` elements of `type`) to `buf` as a buffer view + accessor;
// returns the accessor index. `lo`/`hi`: the POSITION bounds, when given.
int add_float_accessor(tinygltf::Model& m, tinygltf::Buffer& buf, const std::vector<float>& v, size_t nv, int type,
                       const std::array<double, 3>* lo, const std::array<double, 3>* hi) {
  const size_t bytes = v.size() * 4;
  const size_t off = buf.data.size();
  buf.data.resize(off + ((bytes + 3) & ~size_t(3)), 0);
  std::memcpy(buf.data.data() + off, v.data(), bytes);
  tinygltf::BufferView bv;
  bv.buffer = 0;
  bv.byteOffset = off;
  bv.byteLength = v.size() * 4;
  bv.target = TINYGLTF_TARGET_ARRAY_BUFFER;
  m.bufferViews.push_back(bv);
  tinygltf::Accessor a;
  a.bufferView = int(m.bufferViews.size()) - 1;
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.count = nv;
  a.type = type;
  if (lo) {
    a.minValues = {(*lo)[0], (*lo)[1], (*lo)[2]};
    a.maxValues = {(*hi)[0], (*hi)[1], (*hi)[2]};
  }
  m.accessors.push_back(a);
  return int(m.accessors.size()) - 1;
}

// One mesh with a TRIANGLES primitive per material that has triangles.
tinygltf::Mesh add_geometry(tinygltf::Model& m, tinygltf::Buffer& buf, const Scene& scene) {
  tinygltf::Mesh mesh;
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
    for (size_t i = 0; i < pos.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], double(pos[i]));
      hi[i % 3] = std::max(hi[i % 3], double(pos[i]));
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.attributes["POSITION"] = add_float_accessor(m, buf, pos, nv, TINYGLTF_TYPE_VEC3, &lo, &hi);
    prim.attributes["TEXCOORD_0"] = add_float_accessor(m, buf, uv, nv, TINYGLTF_TYPE_VEC2, nullptr, nullptr);
    prim.material = int(mi);
    mesh.primitives.push_back(prim);
  }
  return mesh;
}

// The camera-rig hint of a built-in scene, kept in the glTF scene's extras so that an exported
// scene simulates from the same cameras: {"evflow_view": {"target": [x, y, z], "radius": r,
// "height": h}}.
constexpr const char* kViewExtra = "evflow_view";

tinygltf::Value view_hint_value(const Scene& scene) {
  tinygltf::Value::Array target;
  for (float v : scene.view_target) target.push_back(tinygltf::Value(double(v)));
  tinygltf::Value::Object view{{"target", tinygltf::Value(target)},
                               {"radius", tinygltf::Value(double(scene.view_radius))},
                               {"height", tinygltf::Value(double(scene.view_height))}};
  return tinygltf::Value(tinygltf::Value::Object{{kViewExtra, tinygltf::Value(view)}});
}

void read_view_hint(const Reader& rd, const tinygltf::Value& extras, Scene& s) {
  if (!extras.IsObject() || !extras.Has(kViewExtra)) return;
  const tinygltf::Value& v = extras.Get(kViewExtra);
  auto number = [&](const tinygltf::Value& x, const std::string& what) {
    if (!x.IsNumber() || !std::isfinite(x.GetNumberAsDouble()))
      rd.fail(std::string("scene extras '") + kViewExtra + "': '" + what + "' is not a finite number");
    return float(x.GetNumberAsDouble());
  };
  if (!v.IsObject() || !v.Get("target").IsArray() || v.Get("target").ArrayLen() != 3)
    rd.fail(std::string("scene extras '") + kViewExtra + "' needs 'target' [x, y, z], 'radius' and 'height'");
  for (int k = 0; k < 3; ++k) s.view_target[k] = number(v.Get("target").Get(k), "target");
  s.view_radius = number(v.Get("radius"), "radius");
  s.view_height = number(v.Get("height"), "height");
  if (!(s.view_radius > 0)) rd.fail(std::string("scene extras '") + kViewExtra + "': 'radius' must be positive");
  s.has_view_hint = true;
}

}  // namespace

Scene load_gltf(const fs::path& path) {
  const std::string file = path.string();
  const tinygltf::Model model = read_model(path);
  Reader rd{model, file};
  Scene s;
  s.source = file;
  SceneBuilder b{rd, s, {}};
  b.materials();
  b.visit_roots();
  const int sc = model.defaultScene >= 0 && model.defaultScene < int(model.scenes.size()) ? model.defaultScene : 0;
  if (sc < int(model.scenes.size())) read_view_hint(rd, model.scenes[sc].extras, s);
  if (b.used_default) s.materials.push_back(Material{"default", {1, 1, 1, 1}, -1});
  if (s.triangle_count() == 0) rd.fail("the scene has no triangles");
  s.validate();
  return s;
}

void write_gltf(const Scene& scene, const fs::path& path) {
  scene.validate();
  tinygltf::Model m;
  m.asset.version = "2.0";
  m.asset.generator = "evflow simulate";
  tinygltf::Buffer buf;
  add_textures(m, scene);
  add_materials(m, scene);
  tinygltf::Mesh mesh = add_geometry(m, buf, scene);
  m.buffers.push_back(buf);
  m.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  m.nodes.push_back(node);
  tinygltf::Scene sc;
  sc.nodes = {0};
  if (scene.has_view_hint) sc.extras = view_hint_value(scene);
  m.scenes.push_back(sc);
  m.defaultScene = 0;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  io::write_file_atomic(path, [&](const fs::path& tmp) {
    tinygltf::TinyGLTF w;
    if (!w.WriteGltfSceneToFile(&m, tmp.string(), true, true, ext != ".glb", ext == ".glb"))
      throw std::runtime_error(path.string() + ": cannot write glTF");
  });
}

}  // namespace evflow::sim
