// glTF KHR_gaussian_splatting writer and reader, on nlohmann::json directly (not tinygltf): the
// reader must bounds-check every index and offset of untrusted files and name what is wrong, and
// the writer needs nothing beyond JSON plus one binary buffer.
#include "io/gltf_splats.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/atomic_file.h"

namespace evflow::io {

namespace fs = std::filesystem;
using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;
static_assert(std::endian::native == std::endian::little, "glTF I/O assumes a little-endian host");

namespace {

constexpr const char* kExt = "KHR_gaussian_splatting";
constexpr const char* kRotation = "KHR_gaussian_splatting:ROTATION";
constexpr const char* kScale = "KHR_gaussian_splatting:SCALE";
constexpr const char* kOpacity = "KHR_gaussian_splatting:OPACITY";
constexpr const char* kShPrefix = "KHR_gaussian_splatting:SH_DEGREE_";
constexpr double kShC0 = 0.28209479177387814;
constexpr uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123;
constexpr int kArrayBuffer = 34962;
// Opacity is clamped into [kOpacityEps, 1 - kOpacityEps] before the logit on import.
constexpr double kOpacityEps = 1e-6;
constexpr double kMinScale = 1e-30;  // scale 0 imports as log(kMinScale)

std::string sh_name(int l, int n) { return std::string(kShPrefix) + std::to_string(l) + "_COEF_" + std::to_string(n); }

const char* color_space_name(GltfColorSpace c) {
  return c == GltfColorSpace::lin_rec709_display ? "lin_rec709_display" : "srgb_rec709_display";
}

// ---------------------------------------------------------------------------------------------
// Base64 (RFC 4648, with padding)

constexpr char kB64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

std::string base64_encode(const std::vector<uint8_t>& in) {
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= in.size(); i += 3) {
    const uint32_t v = (uint32_t(in[i]) << 16) | (uint32_t(in[i + 1]) << 8) | in[i + 2];
    for (int s = 18; s >= 0; s -= 6) out += kB64[(v >> s) & 63];
  }
  if (i < in.size()) {
    uint32_t v = uint32_t(in[i]) << 16;
    if (i + 1 < in.size()) v |= uint32_t(in[i + 1]) << 8;
    out += kB64[(v >> 18) & 63];
    out += kB64[(v >> 12) & 63];
    out += i + 1 < in.size() ? kB64[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// Returns false on a character outside the alphabet or bad padding.
bool base64_decode(std::string_view in, std::vector<uint8_t>& out) {
  out.clear();
  out.reserve(in.size() / 4 * 3);
  uint32_t acc = 0;
  int bits = 0;
  size_t pad = 0;
  for (char ch : in) {
    int v;
    if (ch >= 'A' && ch <= 'Z')
      v = ch - 'A';
    else if (ch >= 'a' && ch <= 'z')
      v = ch - 'a' + 26;
    else if (ch >= '0' && ch <= '9')
      v = ch - '0' + 52;
    else if (ch == '+')
      v = 62;
    else if (ch == '/')
      v = 63;
    else if (ch == '=') {
      ++pad;
      continue;
    } else
      return false;
    if (pad) return false;  // data after padding
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t((acc >> bits) & 0xFF));
    }
  }
  return pad <= 2;
}

// ---------------------------------------------------------------------------------------------
// Writing

struct BinaryBuilder {
  std::vector<uint8_t> bin;
  ordered_json buffer_views = ordered_json::array();
  ordered_json accessors = ordered_json::array();

  // Appends `values` (count * components floats) as one tightly packed vertex bufferView and a
  // FLOAT accessor; returns the accessor index.
  int add(const std::vector<float>& values, size_t count, const char* type, int components, bool with_min_max) {
    const size_t offset = bin.size();  // always a multiple of 4: only floats are written
    bin.resize(offset + values.size() * sizeof(float));
    std::memcpy(bin.data() + offset, values.data(), values.size() * sizeof(float));
    buffer_views.push_back({{"buffer", 0},
                            {"byteOffset", offset},
                            {"byteLength", values.size() * sizeof(float)},
                            {"target", kArrayBuffer}});
    ordered_json acc = {
        {"bufferView", buffer_views.size() - 1}, {"componentType", kFloat}, {"count", count}, {"type", type}};
    if (with_min_max) {
      std::vector<float> lo(components, std::numeric_limits<float>::infinity()),
          hi(components, -std::numeric_limits<float>::infinity());
      for (size_t i = 0; i < count; ++i)
        for (int c = 0; c < components; ++c) {
          lo[c] = std::min(lo[c], values[i * components + c]);
          hi[c] = std::max(hi[c], values[i * components + c]);
        }
      acc["min"] = lo;  // floats widen exactly to double and print round-trip exact
      acc["max"] = hi;
    }
    accessors.push_back(std::move(acc));
    return static_cast<int>(accessors.size() - 1);
  }
};

double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

struct GltfContent {
  ordered_json doc;
  std::vector<uint8_t> bin;
};

GltfContent build_gltf(const fs::path& path, const GaussianCloud& cloud, const GltfExportOptions& options) {
  const size_t n = cloud.size();
  const int K = cloud.coeffs();
  BinaryBuilder b;
  ordered_json attributes = ordered_json::object();

  attributes["POSITION"] = b.add(cloud.means, n, "VEC3", 3, true);

  std::vector<float> rot(n * 4), scale(n * 3), opacity(n);
  for (size_t g = 0; g < n; ++g) {
    const float* q = &cloud.quats[g * 4];  // w x y z
    const double norm =
        std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
    if (norm > 1e-30) {
      for (int a = 0; a < 3; ++a) rot[g * 4 + a] = static_cast<float>(q[a + 1] / norm);
      rot[g * 4 + 3] = static_cast<float>(q[0] / norm);
    } else {  // degenerate quaternion: the identity rotation (documented in docs/export.md)
      rot[g * 4 + 0] = rot[g * 4 + 1] = rot[g * 4 + 2] = 0.0f;
      rot[g * 4 + 3] = 1.0f;
    }
    for (int a = 0; a < 3; ++a) {
      const double s = std::exp(double(cloud.log_scales[g * 3 + a]));
      if (!(s <= std::numeric_limits<float>::max()))
        throw std::invalid_argument(path.string() + ": Gaussian " + std::to_string(g) + " has log scale " +
                                    std::to_string(cloud.log_scales[g * 3 + a]) + ", whose exp() overflows float");
      scale[g * 3 + a] = static_cast<float>(s);
    }
    opacity[g] = static_cast<float>(1.0 / (1.0 + std::exp(-double(cloud.opacity_logits[g]))));
  }
  attributes[kRotation] = b.add(rot, n, "VEC4", 4, false);
  attributes[kScale] = b.add(scale, n, "VEC3", 3, false);
  attributes[kOpacity] = b.add(opacity, n, "SCALAR", 1, false);

  std::vector<float> coef(n * 3);
  for (int l = 0; l <= cloud.sh_degree; ++l)
    for (int m = 0; m <= 2 * l; ++m) {
      const int k = l * l + m;  // our coefficient index: degree l, order m - l
      for (size_t g = 0; g < n; ++g)
        for (int c = 0; c < 3; ++c) coef[g * 3 + c] = cloud.sh[(g * K + k) * 3 + c];
      attributes[sh_name(l, m)] = b.add(coef, n, "VEC3", 3, false);
    }

  if (options.color_fallback) {
    std::vector<float> color(n * 4);
    for (size_t g = 0; g < n; ++g) {
      for (int c = 0; c < 3; ++c) {
        double v = std::clamp(kShC0 * cloud.sh[g * K * 3 + c] + 0.5, 0.0, 1.0);
        if (options.color_space == GltfColorSpace::srgb_rec709_display) v = srgb_to_linear(v);  // COLOR_0 is linear
        color[g * 4 + c] = static_cast<float>(v);
      }
      color[g * 4 + 3] = opacity[g];
    }
    attributes["COLOR_0"] = b.add(color, n, "VEC4", 4, false);
  }

  ordered_json primitive = {{"mode", 0},
                            {"attributes", attributes},
                            {"extensions",
                             {{kExt,
                               {{"kernel", "ellipse"},
                                {"colorSpace", color_space_name(options.color_space)},
                                {"projection", "perspective"},
                                {"sortingMethod", "cameraDistance"}}}}}};
  GltfContent out;
  out.doc = {{"asset", {{"version", "2.0"}, {"generator", "EvFlow"}}},
             {"extensionsUsed", ordered_json::array({kExt})},
             {"scene", 0},
             {"scenes", ordered_json::array({{{"nodes", ordered_json::array({0})}}})},
             {"nodes", {{{"name", "gaussians"}, {"mesh", 0}}}},
             {"meshes", {{{"name", "gaussians"}, {"primitives", {primitive}}}}},
             {"buffers", {{{"byteLength", b.bin.size()}}}},
             {"bufferViews", std::move(b.buffer_views)},
             {"accessors", std::move(b.accessors)}};
  out.bin = std::move(b.bin);
  return out;
}

void put_u32(std::string& s, uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  s.append(b, 4);
}

void write_bytes(const fs::path& tmp, const fs::path& target, const std::string& head,
                 const std::vector<uint8_t>& tail) {
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(tmp.string() + ": cannot open for writing");
  out.write(head.data(), static_cast<std::streamsize>(head.size()));
  out.write(reinterpret_cast<const char*>(tail.data()), static_cast<std::streamsize>(tail.size()));
  close_or_throw(out, target);
}

// ---------------------------------------------------------------------------------------------
// Reading

// Thrown inside the reader; read_gltf_splats() prefixes the file name.
struct GltfError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

uint32_t get_u32(const std::vector<uint8_t>& b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

const json& member(const json& obj, const std::string& key, const std::string& where) {
  if (!obj.is_object()) throw GltfError(where + " is not a JSON object");
  const auto it = obj.find(key);
  if (it == obj.end()) throw GltfError(where + " lacks '" + key + "'");
  return *it;
}

uint64_t as_uint(const json& v, const std::string& where) {
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
    throw GltfError(where + " must be a non-negative integer, found " + v.dump().substr(0, 40));
  return v.get<uint64_t>();
}

uint64_t uint_or(const json& obj, const std::string& key, uint64_t fallback, const std::string& where) {
  const auto it = obj.find(key);
  return it == obj.end() ? fallback : as_uint(*it, where + "." + key);
}

const json& element(const json& doc, const char* array, uint64_t index, const std::string& referrer) {
  const auto it = doc.find(array);
  if (it == doc.end() || !it->is_array() || index >= it->size())
    throw GltfError(referrer + " refers to " + array + "[" + std::to_string(index) + "], which does not exist");
  return (*it)[index];
}

struct Document {
  fs::path path;
  json doc;
  std::vector<uint8_t> glb_bin;
  bool has_glb_bin = false;
  std::vector<std::vector<uint8_t>> buffers;
  std::vector<bool> buffer_loaded;
};

const std::vector<uint8_t>& buffer_data(Document& d, uint64_t index, const std::string& referrer) {
  const json& buf = element(d.doc, "buffers", index, referrer);
  const std::string where = "buffers[" + std::to_string(index) + "]";
  if (d.buffers.size() != d.doc["buffers"].size()) {
    d.buffers.assign(d.doc["buffers"].size(), {});
    d.buffer_loaded.assign(d.doc["buffers"].size(), false);
  }
  if (d.buffer_loaded[index]) return d.buffers[index];
  const uint64_t byte_length = as_uint(member(buf, "byteLength", where), where + ".byteLength");
  std::vector<uint8_t>& data = d.buffers[index];
  const auto uri_it = buf.find("uri");
  if (uri_it == buf.end()) {
    if (index != 0 || !d.has_glb_bin) throw GltfError(where + " has no uri and there is no GLB BIN chunk for it");
    data = d.glb_bin;
  } else {
    if (!uri_it->is_string()) throw GltfError(where + ".uri is not a string");
    const std::string& uri = uri_it->get_ref<const std::string&>();
    if (uri.rfind("data:", 0) == 0) {
      const size_t comma = uri.find(',');
      if (comma == std::string::npos || uri.substr(0, comma).find(";base64") == std::string::npos)
        throw GltfError(where + ".uri is a data URI without base64 payload");
      if (!base64_decode(std::string_view(uri).substr(comma + 1), data))
        throw GltfError(where + ".uri has invalid base64 data");
    } else {
      // A relative URI reference, percent-encoded (RFC 3986).
      std::string decoded;
      for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
          decoded += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
          i += 2;
        } else {
          decoded += uri[i];
        }
      }
      const fs::path file = d.path.parent_path() / fs::path(decoded);
      std::ifstream in(file, std::ios::binary);
      if (!in) throw GltfError(where + ".uri: cannot open external buffer " + file.string());
      data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
  }
  if (data.size() < byte_length)
    throw GltfError(where + " declares byteLength " + std::to_string(byte_length) + " but holds only " +
                    std::to_string(data.size()) + " bytes (truncated)");
  data.resize(static_cast<size_t>(byte_length));
  d.buffer_loaded[index] = true;
  return data;
}

int type_components(const std::string& t) {
  if (t == "SCALAR") return 1;
  if (t == "VEC2") return 2;
  if (t == "VEC3") return 3;
  if (t == "VEC4") return 4;
  return 0;
}

size_t component_size(int ct) {
  switch (ct) {
    case kByte:
    case kUByte:
      return 1;
    case kShort:
    case kUShort:
      return 2;
    case kFloat:
      return 4;
    default:
      return 0;
  }
}

struct Allowed {
  int component_type;
  bool normalized;
};

std::string allowed_list(const std::vector<Allowed>& allowed) {
  std::string s;
  for (const auto& a : allowed) {
    if (!s.empty()) s += ", ";
    s += std::to_string(a.component_type) + (a.normalized ? " normalized" : "");
  }
  return s;
}

// Reads accessor `index` used as attribute `semantic`: `components` values per element, as floats
// (normalised integers mapped per the glTF spec). Returns count * components values.
std::vector<float> read_accessor(Document& d, uint64_t index, const std::string& semantic, const char* expected_type,
                                 const std::vector<Allowed>& allowed, uint64_t& count) {
  const std::string where = "accessors[" + std::to_string(index) + "] (" + semantic + ")";
  const json& acc = element(d.doc, "accessors", index, "attribute " + semantic);
  if (!acc.is_object()) throw GltfError(where + " is not a JSON object");
  if (acc.contains("sparse")) throw GltfError(where + " is sparse, which EvFlow does not read");
  const json& type = member(acc, "type", where);
  if (!type.is_string() || type.get<std::string>() != expected_type)
    throw GltfError(where + " has type " + type.dump().substr(0, 20) + ", expected " + expected_type);
  const int components = type_components(expected_type);
  const uint64_t ct = as_uint(member(acc, "componentType", where), where + ".componentType");
  const auto norm_it = acc.find("normalized");
  const bool normalized = norm_it != acc.end() && norm_it->is_boolean() && norm_it->get<bool>();
  bool ok = false;
  for (const auto& a : allowed) ok = ok || (uint64_t(a.component_type) == ct && a.normalized == normalized);
  if (!ok)
    throw GltfError(where + " has componentType " + std::to_string(ct) + (normalized ? " normalized" : "") +
                    "; allowed: " + allowed_list(allowed));
  count = as_uint(member(acc, "count", where), where + ".count");
  if (count == 0 || count > (uint64_t(1) << 32)) throw GltfError(where + " has count " + std::to_string(count));
  const size_t csize = component_size(int(ct));
  const uint64_t elem = csize * components;

  std::vector<float> out(static_cast<size_t>(count * components), 0.0f);
  const auto bv_it = acc.find("bufferView");
  if (bv_it == acc.end()) return out;  // glTF: an accessor without bufferView holds zeros
  const uint64_t bv_index = as_uint(*bv_it, where + ".bufferView");
  const json& bv = element(d.doc, "bufferViews", bv_index, where);
  const std::string bv_where = "bufferViews[" + std::to_string(bv_index) + "]";
  const uint64_t buffer = as_uint(member(bv, "buffer", bv_where), bv_where + ".buffer");
  const uint64_t bv_offset = uint_or(bv, "byteOffset", 0, bv_where);
  const uint64_t bv_length = as_uint(member(bv, "byteLength", bv_where), bv_where + ".byteLength");
  const uint64_t stride = uint_or(bv, "byteStride", 0, bv_where);
  const uint64_t step = stride ? stride : elem;
  if (step < elem)
    throw GltfError(bv_where + ".byteStride " + std::to_string(stride) + " is smaller than an element of " + where);
  const uint64_t acc_offset = uint_or(acc, "byteOffset", 0, where);
  const std::vector<uint8_t>& data = buffer_data(d, buffer, bv_where);
  if (bv_offset > data.size() || bv_length > data.size() - bv_offset)
    throw GltfError(bv_where + " (offset " + std::to_string(bv_offset) + ", length " + std::to_string(bv_length) +
                    ") runs past the end of buffers[" + std::to_string(buffer) + "] (" + std::to_string(data.size()) +
                    " bytes)");
  // count <= 2^32 and step <= 2^40 keep this product far from overflow; offsets were bounded above.
  if (step > (uint64_t(1) << 40) || acc_offset > bv_length || (count - 1) * step + elem > bv_length - acc_offset)
    throw GltfError(where + " (" + std::to_string(count) + " elements, offset " + std::to_string(acc_offset) +
                    ") does not fit in " + bv_where + " (" + std::to_string(bv_length) + " bytes)");
  const uint8_t* base = data.data() + bv_offset + acc_offset;
  for (uint64_t i = 0; i < count; ++i) {
    const uint8_t* p = base + i * step;
    for (int c = 0; c < components; ++c) {
      const uint8_t* q = p + c * csize;
      double v = 0;
      switch (ct) {
        case kFloat: {
          float f;
          std::memcpy(&f, q, 4);
          v = f;
          break;
        }
        case kByte: {
          int8_t x;
          std::memcpy(&x, q, 1);
          v = normalized ? std::max(x / 127.0, -1.0) : x;
          break;
        }
        case kUByte:
          v = normalized ? q[0] / 255.0 : q[0];
          break;
        case kShort: {
          int16_t x;
          std::memcpy(&x, q, 2);
          v = normalized ? std::max(x / 32767.0, -1.0) : x;
          break;
        }
        case kUShort: {
          uint16_t x;
          std::memcpy(&x, q, 2);
          v = normalized ? x / 65535.0 : x;
          break;
        }
      }
      if (!std::isfinite(v))
        throw GltfError(where + ": element " + std::to_string(i) + " component " + std::to_string(c) +
                        " is not finite");
      out[static_cast<size_t>(i * components + c)] = static_cast<float>(v);
    }
  }
  return out;
}

// One splat primitive, decoded to pre-activation values.
struct SplatPrimitive {
  int degree = 0;
  GaussianCloud cloud;
};

// The primitive's KHR_gaussian_splatting object, checked for what EvFlow can render.
void check_extension(const json& prim, const std::string& where) {
  const json& ext = member(member(prim, "extensions", where), kExt, where + ".extensions");
  const std::string ext_where = where + ".extensions." + kExt;
  const json& kernel = member(ext, "kernel", ext_where);
  if (!kernel.is_string() || kernel.get<std::string>() != "ellipse")
    throw GltfError(ext_where + ".kernel is " + kernel.dump().substr(0, 40) + "; EvFlow reads only \"ellipse\"");
  const json& cs = member(ext, "colorSpace", ext_where);
  if (!cs.is_string() ||
      (cs.get<std::string>() != "srgb_rec709_display" && cs.get<std::string>() != "lin_rec709_display"))
    throw GltfError(ext_where + ".colorSpace is " + cs.dump().substr(0, 40) +
                    "; expected \"srgb_rec709_display\" or \"lin_rec709_display\"");
  if (ext.contains("projection") && ext["projection"] != "perspective")
    throw GltfError(ext_where + ".projection is " + ext["projection"].dump().substr(0, 40) +
                    "; EvFlow renders only \"perspective\"");
  const uint64_t mode = uint_or(prim, "mode", 4, where);
  if (mode != 0)
    throw GltfError(where + " has mode " + std::to_string(mode) + "; KHR_gaussian_splatting requires POINTS (0)");
}

// Marks SH attribute "<prefix><l>_COEF_<n>" present; anything else with the prefix is malformed.
void mark_sh_attribute(const std::string& key, const std::string& where,
                       bool (&present)[kMaxShDegree + 1][2 * kMaxShDegree + 1]) {
  int l = -1, n = -1;
  const std::string_view rest = std::string_view(key).substr(std::strlen(kShPrefix));
  const size_t sep = rest.find("_COEF_");
  const auto parse = [](std::string_view t, int& v) {
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && ptr == t.data() + t.size() && !t.empty() && t.size() <= 3;
  };
  if (sep == std::string_view::npos || !parse(rest.substr(0, sep), l) || !parse(rest.substr(sep + 6), n) || l < 0 ||
      n < 0 || n > 2 * l || key != sh_name(l, n))
    throw GltfError(where + ".attributes has malformed SH attribute '" + key + "'");
  if (l > kMaxShDegree)
    throw GltfError(where + ".attributes has SH degree " + std::to_string(l) + "; EvFlow supports up to 3");
  present[l][n] = true;
}

// The SH degree the attributes define completely (every degree up to it, none above).
int sh_degree(const json& attrs, const std::string& where) {
  bool present[kMaxShDegree + 1][2 * kMaxShDegree + 1] = {};
  for (const auto& [key, value] : attrs.items())
    if (key.rfind(kShPrefix, 0) == 0) mark_sh_attribute(key, where, present);
  int degree = -1;
  for (int l = 0; l <= kMaxShDegree; ++l) {
    int have = 0;
    for (int n = 0; n <= 2 * l; ++n) have += present[l][n];
    if (l == 0 && have == 0) throw GltfError(where + " lacks the required attribute " + sh_name(0, 0));
    if (have == 0) break;
    if (have != 2 * l + 1)
      throw GltfError(where + ": SH degree " + std::to_string(l) + " is partially defined (" + std::to_string(have) +
                      " of " + std::to_string(2 * l + 1) + " coefficients)");
    degree = l;
  }
  for (int l = degree + 1; l <= kMaxShDegree; ++l)
    for (int n = 0; n <= 2 * l; ++n)
      if (present[l][n])
        throw GltfError(where + ": SH degree " + std::to_string(l) + " is present but degree " +
                        std::to_string(degree + 1) + " is not");
  return degree;
}

// Rotation (xyzw), scale and opacity of splat g, activated values checked and inverted.
void store_geometry(GaussianCloud& cloud, uint64_t g, const std::vector<float>& rot, const std::vector<float>& scale,
                    const std::vector<float>& opacity) {
  cloud.quats[g * 4 + 0] = rot[g * 4 + 3];  // xyzw -> wxyz
  for (int a = 0; a < 3; ++a) cloud.quats[g * 4 + 1 + a] = rot[g * 4 + a];
  for (int a = 0; a < 3; ++a) {
    const float s = scale[g * 3 + a];
    if (s < 0)
      throw GltfError(std::string(kScale) + " of splat " + std::to_string(g) + " is negative (" + std::to_string(s) +
                      ")");
    cloud.log_scales[g * 3 + a] = static_cast<float>(std::log(std::max<double>(s, kMinScale)));
  }
  const double o = opacity[g];
  if (o < 0 || o > 1)
    throw GltfError(std::string(kOpacity) + " of splat " + std::to_string(g) + " is outside [0, 1] (" +
                    std::to_string(o) + ")");
  const double oc = std::clamp(o, kOpacityEps, 1.0 - kOpacityEps);
  cloud.opacity_logits[g] = static_cast<float>(std::log(oc / (1.0 - oc)));
}

// Reads a primitive's attribute accessors, each checked to have as many elements as POSITION.
struct AttributeReader {
  Document& d;
  const json& attrs;
  const std::string& where;
  uint64_t n = 0;  // POSITION's count

  std::vector<float> read(const std::string& semantic, const char* type, const std::vector<Allowed>& formats) {
    const auto it = attrs.find(semantic);
    if (it == attrs.end()) throw GltfError(where + " lacks the required attribute " + semantic);
    uint64_t c = 0;
    std::vector<float> v =
        read_accessor(d, as_uint(*it, where + ".attributes." + semantic), semantic, type, formats, c);
    if (semantic == "POSITION")
      n = c;
    else if (c != n)
      throw GltfError(where + ": attribute " + semantic + " has " + std::to_string(c) + " elements but POSITION has " +
                      std::to_string(n));
    return v;
  }
};

SplatPrimitive read_primitive(Document& d, const json& prim, const std::string& where) {
  check_extension(prim, where);
  const json& attrs = member(prim, "attributes", where);
  if (!attrs.is_object()) throw GltfError(where + ".attributes is not an object");
  const int degree = sh_degree(attrs, where);
  AttributeReader in{d, attrs, where};
  const std::vector<float> pos = in.read("POSITION", "VEC3", {{kFloat, false}});
  const std::vector<float> rot = in.read(kRotation, "VEC4", {{kFloat, false}, {kByte, true}, {kShort, true}});
  const std::vector<float> scale =
      in.read(kScale, "VEC3", {{kFloat, false}, {kUByte, false}, {kUByte, true}, {kUShort, false}, {kUShort, true}});
  const std::vector<float> opacity = in.read(kOpacity, "SCALAR", {{kFloat, false}, {kUByte, true}, {kUShort, true}});
  SplatPrimitive out;
  out.degree = degree;
  GaussianCloud& cloud = out.cloud;
  cloud.resize(static_cast<size_t>(in.n), degree);
  const int K = cloud.coeffs();
  cloud.means = pos;
  for (uint64_t g = 0; g < in.n; ++g) store_geometry(cloud, g, rot, scale, opacity);
  for (int l = 0; l <= degree; ++l)
    for (int m = 0; m <= 2 * l; ++m) {
      const std::vector<float> coef = in.read(sh_name(l, m), "VEC3", {{kFloat, false}});
      const int k = l * l + m;
      for (uint64_t g = 0; g < in.n; ++g)
        for (int ch = 0; ch < 3; ++ch) cloud.sh[(g * K + k) * 3 + ch] = coef[g * 3 + ch];
    }
  return out;
}

// A GLB container: its JSON chunk and, when there is one, its BIN chunk.
void read_glb(Document& d, const std::vector<uint8_t>& bytes) {
  if (bytes.size() < 20) throw GltfError("GLB shorter than its 12-byte header and first chunk header (truncated)");
  const uint32_t version = get_u32(bytes, 4), length = get_u32(bytes, 8);
  if (version != 2) throw GltfError("GLB version " + std::to_string(version) + ", expected 2");
  if (length > bytes.size())
    throw GltfError("GLB header declares " + std::to_string(length) + " bytes but the file has " +
                    std::to_string(bytes.size()) + " (truncated)");
  const uint32_t json_len = get_u32(bytes, 12), json_type = get_u32(bytes, 16);
  if (json_type != kChunkJson) throw GltfError("the first GLB chunk is not JSON");
  if (json_len > length - 20) throw GltfError("the GLB JSON chunk runs past the end of the file (truncated)");
  d.doc = json::parse(bytes.begin() + 20, bytes.begin() + 20 + json_len, nullptr, false);
  if (d.doc.is_discarded()) throw GltfError("the GLB JSON chunk is not valid JSON");
  size_t at = 20 + size_t(json_len);
  at = (at + 3) & ~size_t(3);
  if (at + 8 > length) return;
  const uint32_t bin_len = get_u32(bytes, at), bin_type = get_u32(bytes, at + 4);
  if (bin_type != kChunkBin) return;
  if (bin_len > length - at - 8) throw GltfError("the GLB BIN chunk runs past the end of the file (truncated)");
  d.glb_bin.assign(bytes.begin() + at + 8, bytes.begin() + at + 8 + bin_len);
  d.has_glb_bin = true;
}

// The document of a GLB or a .gltf JSON file, its asset version and required extensions checked.
void read_document(Document& d, const std::vector<uint8_t>& bytes) {
  if (bytes.size() >= 4 && get_u32(bytes, 0) == kGlbMagic) {
    read_glb(d, bytes);
  } else {
    size_t start = 0;
    if (bytes.size() >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF) start = 3;  // UTF-8 BOM
    d.doc = json::parse(bytes.begin() + start, bytes.end(), nullptr, false);
    if (d.doc.is_discarded()) throw GltfError("not a glTF file: neither GLB (no 'glTF' magic) nor valid JSON");
  }
  const json& doc = d.doc;
  if (!doc.is_object()) throw GltfError("the glTF JSON is not an object");
  const json& asset = member(doc, "asset", "glTF");
  const json& version = member(asset, "version", "asset");
  if (!version.is_string() || version.get<std::string>().rfind("2.", 0) != 0)
    throw GltfError("asset.version is " + version.dump().substr(0, 20) + ", expected \"2.x\"");
  if (!doc.contains("extensionsRequired")) return;
  const json& req = doc["extensionsRequired"];
  if (!req.is_array()) throw GltfError("extensionsRequired is not an array");
  for (const auto& e : req)
    if (e != kExt)
      throw GltfError("the file requires extension " + e.dump().substr(0, 60) + ", which EvFlow cannot read");
}

// Every mesh primitive that carries the extension; they must agree on the colour space.
std::vector<SplatPrimitive> read_primitives(Document& d, std::string& color_space) {
  std::vector<SplatPrimitive> prims;
  if (!d.doc.contains("meshes")) return prims;
  const json& meshes = d.doc["meshes"];
  if (!meshes.is_array()) throw GltfError("meshes is not an array");
  for (size_t mi = 0; mi < meshes.size(); ++mi) {
    const std::string mw = "meshes[" + std::to_string(mi) + "]";
    const json& primitives = member(meshes[mi], "primitives", mw);
    if (!primitives.is_array()) throw GltfError(mw + ".primitives is not an array");
    for (size_t pi = 0; pi < primitives.size(); ++pi) {
      const json& prim = primitives[pi];
      if (!prim.is_object() || !prim.contains("extensions") || !prim["extensions"].is_object() ||
          !prim["extensions"].contains(kExt))
        continue;
      prims.push_back(read_primitive(d, prim, mw + ".primitives[" + std::to_string(pi) + "]"));
      const std::string cs = prim["extensions"][kExt]["colorSpace"].get<std::string>();
      if (color_space.empty())
        color_space = cs;
      else if (cs != color_space)
        throw GltfError("splat primitives disagree on colorSpace (" + color_space + " vs " + cs + ")");
    }
  }
  return prims;
}

// Several primitives concatenated at the highest SH degree, missing coefficients zero.
GaussianCloud concatenate(const std::vector<SplatPrimitive>& prims) {
  int degree = 0;
  size_t total = 0;
  for (const auto& p : prims) {
    degree = std::max(degree, p.degree);
    total += p.cloud.size();
  }
  GaussianCloud cloud;
  cloud.resize(total, degree);
  const int K = cloud.coeffs();
  size_t at = 0;
  for (const auto& p : prims) {
    const GaussianCloud& c = p.cloud;
    const size_t n = c.size();
    std::copy(c.means.begin(), c.means.end(), cloud.means.begin() + at * 3);
    std::copy(c.log_scales.begin(), c.log_scales.end(), cloud.log_scales.begin() + at * 3);
    std::copy(c.quats.begin(), c.quats.end(), cloud.quats.begin() + at * 4);
    std::copy(c.opacity_logits.begin(), c.opacity_logits.end(), cloud.opacity_logits.begin() + at);
    const int Kc = c.coeffs();
    for (size_t g = 0; g < n; ++g)
      for (int k = 0; k < Kc; ++k)
        for (int ch = 0; ch < 3; ++ch) cloud.sh[((at + g) * K + k) * 3 + ch] = c.sh[(g * Kc + k) * 3 + ch];
    at += n;
  }
  return cloud;
}

GaussianCloud parse_gltf(const fs::path& path, const std::vector<uint8_t>& bytes, GltfColorSpace* color_space) {
  Document d;
  d.path = path;
  read_document(d, bytes);
  std::string first_color_space;
  std::vector<SplatPrimitive> prims = read_primitives(d, first_color_space);
  if (prims.empty()) throw GltfError("no mesh primitive carries KHR_gaussian_splatting: not a Gaussian-splat glTF");
  if (color_space)
    *color_space = first_color_space == "lin_rec709_display" ? GltfColorSpace::lin_rec709_display
                                                             : GltfColorSpace::srgb_rec709_display;
  if (prims.size() == 1) return std::move(prims[0].cloud);
  return concatenate(prims);
}

}  // namespace

void write_gltf_splats(const fs::path& path, const GaussianCloud& cloud, const GltfExportOptions& options) {
  cloud.validate(path.string());
  if (cloud.size() == 0)
    throw std::invalid_argument(path.string() + ": cannot export an empty cloud to glTF (accessors need count >= 1)");
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  if (ext != ".glb" && ext != ".gltf")
    throw std::invalid_argument(path.string() + ": unknown glTF extension '" + ext + "'; use .glb or .gltf");
  GltfContent content = build_gltf(path, cloud, options);
  if (ext == ".gltf") {
    content.doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64_encode(content.bin);
    const std::string text = content.doc.dump(1) + "\n";
    write_file_atomic(path, [&](const fs::path& tmp) { write_bytes(tmp, path, text, {}); });
    return;
  }
  std::string json_text = content.doc.dump();
  while (json_text.size() % 4) json_text += ' ';
  const uint64_t total = 12 + 8 + json_text.size() + 8 + content.bin.size();
  if (total > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument(path.string() + ": the cloud needs " + std::to_string(total) +
                                " bytes, more than GLB's 4 GiB limit");
  std::string head;
  head.reserve(20 + json_text.size() + 8);
  put_u32(head, kGlbMagic);
  put_u32(head, 2);
  put_u32(head, static_cast<uint32_t>(total));
  put_u32(head, static_cast<uint32_t>(json_text.size()));
  put_u32(head, kChunkJson);
  head += json_text;
  put_u32(head, static_cast<uint32_t>(content.bin.size()));  // already a multiple of 4
  put_u32(head, kChunkBin);
  write_file_atomic(path, [&](const fs::path& tmp) { write_bytes(tmp, path, head, content.bin); });
}

GaussianCloud read_gltf_splats(const fs::path& path, GltfColorSpace* color_space) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open glTF file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path.string() + ": read error");
  try {
    return parse_gltf(path, bytes, color_space);
  } catch (const GltfError& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  } catch (const json::exception& e) {
    throw std::runtime_error(path.string() + ": malformed glTF JSON: " + e.what());
  } catch (const std::bad_alloc&) { throw std::runtime_error(path.string() + ": glTF too large to load"); }
}

}  // namespace evflow::io
