// Splat export/import (engine/io/ply_splats, engine/io/gltf_splats): round trips, hand-written
// Inria PLY, malformed inputs, atomic writes, and the Khronos glTF validator.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cli_helpers.h"
#include "gpu_fixture.h"
#include "io/gltf_splats.h"
#include "io/ply_splats.h"
#include "reference/srgb_reference.h"
#include "splat/rasterizer.h"

namespace fs = std::filesystem;
using namespace evflow;
using namespace evflow::io;
using Catch::Contains;
using json = nlohmann::json;

namespace {

struct TmpDir {
  fs::path path;
  TmpDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("evflow_test_export_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path);
  }
  ~TmpDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path operator/(const std::string& name) const { return path / name; }
};

// Random cloud; the first Gaussians carry extreme opacities (logits +-20) to exercise clamping.
GaussianCloud random_cloud(size_t n, int degree, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  GaussianCloud c;
  c.resize(n, degree);
  for (auto& v : c.means) v = 5.0f * u(rng);
  for (auto& v : c.log_scales) v = -2.0f + 3.0f * u(rng);
  for (auto& v : c.quats) v = normal(rng);
  for (auto& v : c.opacity_logits) v = 6.0f * u(rng);
  for (auto& v : c.sh) v = u(rng);
  if (n > 2) {
    c.opacity_logits[0] = 20.0f;
    c.opacity_logits[1] = -20.0f;
  }
  return c;
}

std::vector<uint8_t> read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& p, const std::vector<uint8_t>& b) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

void write_text(const fs::path& p, const std::string& s) { write_bytes(p, std::vector<uint8_t>(s.begin(), s.end())); }

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// GLB <-> (JSON, BIN) for tampering with files we wrote.
struct Glb {
  json doc;
  std::vector<uint8_t> bin;
};

Glb split_glb(const std::vector<uint8_t>& b) {
  uint32_t json_len, bin_len;
  std::memcpy(&json_len, b.data() + 12, 4);
  Glb g;
  g.doc = json::parse(b.begin() + 20, b.begin() + 20 + json_len);
  std::memcpy(&bin_len, b.data() + 20 + json_len, 4);
  g.bin.assign(b.begin() + 28 + json_len, b.begin() + 28 + json_len + bin_len);
  return g;
}

std::vector<uint8_t> join_glb(const Glb& g) {
  std::string text = g.doc.dump();
  while (text.size() % 4) text += ' ';
  std::vector<uint8_t> out;
  auto u32 = [&](uint32_t v) {
    uint8_t b[4];
    std::memcpy(b, &v, 4);
    out.insert(out.end(), b, b + 4);
  };
  u32(0x46546C67);
  u32(2);
  u32(static_cast<uint32_t>(28 + text.size() + g.bin.size()));
  u32(static_cast<uint32_t>(text.size()));
  u32(0x4E4F534A);
  out.insert(out.end(), text.begin(), text.end());
  u32(static_cast<uint32_t>(g.bin.size()));
  u32(0x004E4942);
  out.insert(out.end(), g.bin.begin(), g.bin.end());
  return out;
}

// Loading must either succeed or throw std::runtime_error naming the file; anything else fails.
template <typename Reader>
void expect_load_or_clean_error(Reader read, const fs::path& p) {
  try {
    read(p);
  } catch (const std::runtime_error& e) { REQUIRE_THAT(e.what(), Contains(p.string())); }
}

}  // namespace

// --------------------------------------------------------------------------------------------
// PLY

TEST_CASE("PLY round trip reproduces every parameter exactly, SH degrees 0..3", "[export]") {
  TmpDir dir;
  for (int degree = 0; degree <= 3; ++degree) {
    const GaussianCloud c = random_cloud(257, degree, 100 + degree);
    const fs::path p = dir / ("cloud" + std::to_string(degree) + ".ply");
    write_ply(p, c);
    const GaussianCloud r = read_ply(p);
    CAPTURE(degree);
    REQUIRE(r.sh_degree == degree);
    REQUIRE(r.size() == c.size());
    REQUIRE(r.means == c.means);
    REQUIRE(r.log_scales == c.log_scales);
    REQUIRE(r.quats == c.quats);
    REQUIRE(r.opacity_logits == c.opacity_logits);
    REQUIRE(r.sh == c.sh);
    // The header is exactly the Inria one.
    const auto bytes = read_bytes(p);
    const std::string text(bytes.begin(), bytes.end());
    const size_t end = text.find("end_header\n");
    REQUIRE(end != std::string::npos);
    const int rest = 3 * (sh_coeff_count(degree) - 1);
    REQUIRE(bytes.size() == end + 11 + c.size() * (17 + rest) * 4);
    const std::string header = text.substr(0, end);
    REQUIRE(header.rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
    REQUIRE_THAT(header, Contains("\nelement vertex 257\nproperty float x\nproperty float y\n"
                                  "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                                  "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\n"));
    REQUIRE_THAT(header, Contains("property float opacity\nproperty float scale_0\nproperty float scale_1\n"
                                  "property float scale_2\nproperty float rot_0\nproperty float rot_1\n"
                                  "property float rot_2\nproperty float rot_3\n"));
    REQUIRE((rest == 0) == (header.find("f_rest_0") == std::string::npos));
    if (rest)
      REQUIRE_THAT(header, Contains("property float f_rest_" + std::to_string(rest - 1) + "\nproperty float opacity"));
    // f_rest is channel-major: the first f_rest of vertex 0 is coefficient 1 of red, f_rest[K-1] is
    // coefficient 1 of green.
    if (degree == 3) {
      float v[2];
      std::memcpy(&v[0], bytes.data() + end + 11 + 9 * 4, 4);
      std::memcpy(&v[1], bytes.data() + end + 11 + (9 + 15) * 4, 4);
      REQUIRE(v[0] == c.sh[1 * 3 + 0]);
      REQUIRE(v[1] == c.sh[1 * 3 + 1]);
    }
  }
  // An empty cloud is a valid PLY too.
  GaussianCloud empty;
  empty.resize(0, 2);
  write_ply(dir / "empty.ply", empty);
  const GaussianCloud r = read_ply(dir / "empty.ply");
  REQUIRE(r.size() == 0);
  REQUIRE(r.sh_degree == 2);
}

namespace {

// A two-Gaussian, SH degree 1 cloud with known values, for the hand-written files.
GaussianCloud hand_cloud() {
  GaussianCloud c;
  c.resize(2, 1);
  for (size_t g = 0; g < 2; ++g) {
    for (int a = 0; a < 3; ++a) {
      c.means[g * 3 + a] = 0.5f * float(g) + float(a) - 1.25f;
      c.log_scales[g * 3 + a] = -1.0f - 0.25f * float(a) - float(g);
    }
    for (int a = 0; a < 4; ++a) c.quats[g * 4 + a] = 0.125f * float(a + 1) + float(g);
    c.opacity_logits[g] = g ? -2.5f : 1.75f;
    for (int k = 0; k < 4; ++k)
      for (int ch = 0; ch < 3; ++ch) c.sh[(g * 4 + k) * 3 + ch] = 0.01f * float(100 * int(g) + 10 * k + ch) - 0.3f;
  }
  return c;
}

// Value of the Inria property `name` of Gaussian g of the hand cloud (degree 1: f_rest_0..8).
double inria_value(const GaussianCloud& c, size_t g, const std::string& name) {
  const int K = c.coeffs();
  if (name == "x" || name == "y" || name == "z") return c.means[g * 3 + (name[0] - 'x')];
  if (name.rfind("f_dc_", 0) == 0) return c.sh[g * K * 3 + std::stoi(name.substr(5))];
  if (name.rfind("f_rest_", 0) == 0) {
    const int i = std::stoi(name.substr(7)), ch = i / (K - 1), k = 1 + i % (K - 1);
    return c.sh[(g * K + k) * 3 + ch];
  }
  if (name == "opacity") return c.opacity_logits[g];
  if (name.rfind("scale_", 0) == 0) return c.log_scales[g * 3 + std::stoi(name.substr(6))];
  if (name.rfind("rot_", 0) == 0) return c.quats[g * 4 + std::stoi(name.substr(4))];
  return 0;  // nx, ny, nz
}

template <typename T>
void append(std::vector<uint8_t>& out, T v) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

}  // namespace

TEST_CASE("a hand-written Inria PLY with another property order loads", "[export]") {
  TmpDir dir;
  const GaussianCloud c = hand_cloud();
  // Scrambled order, some doubles, an extra uchar colour, a comment and an element before the
  // vertices that must be skipped.
  struct Prop {
    std::string name;
    bool is_double;
  };
  std::vector<Prop> props = {{"rot_3", false},    {"opacity", true},   {"f_rest_8", false}, {"x", true},
                             {"scale_2", false},  {"f_dc_1", false},   {"nx", false},       {"f_rest_0", false},
                             {"rot_0", false},    {"y", false},        {"f_rest_4", true},  {"scale_0", false},
                             {"f_rest_1", false}, {"f_dc_0", false},   {"rot_2", false},    {"f_rest_2", false},
                             {"z", false},        {"f_rest_3", false}, {"f_rest_5", false}, {"scale_1", false},
                             {"f_rest_6", false}, {"f_dc_2", true},    {"f_rest_7", false}, {"rot_1", false}};

  for (const std::string format : {"binary_little_endian", "ascii"}) {
    CAPTURE(format);
    const bool ascii = format == "ascii";
    std::string header = "ply\r\nformat " + format +
                         " 1.0\ncomment written by hand\nelement camera 2\nproperty int id\n"
                         "property float fov\nelement vertex 2\n";
    for (const auto& p : props)
      header += std::string("property ") + (p.is_double ? "double " : "float ") + p.name + "\n";
    header += "property uchar red\nend_header\n";
    std::vector<uint8_t> file(header.begin(), header.end());
    std::string body;
    if (ascii)
      body = "7 0.5\n8 1.5\n";
    else
      for (int i = 0; i < 2; ++i) {
        append<int32_t>(file, 7 + i);
        append<float>(file, 0.5f + i);
      }
    for (size_t g = 0; g < 2; ++g) {
      for (const auto& p : props) {
        const double v = inria_value(c, g, p.name);
        if (ascii) {
          char buf[64];
          std::snprintf(buf, sizeof buf, "%.9g ", v);
          body += buf;
        } else if (p.is_double)
          append<double>(file, v);
        else
          append<float>(file, static_cast<float>(v));
      }
      if (ascii)
        body += "200\n";
      else
        append<uint8_t>(file, 200);
    }
    file.insert(file.end(), body.begin(), body.end());
    const fs::path path = dir / ("hand_" + format + ".ply");
    write_bytes(path, file);
    const GaussianCloud r = read_ply(path);
    REQUIRE(r.sh_degree == 1);
    REQUIRE(r.size() == 2);
    REQUIRE(r.means == c.means);
    REQUIRE(r.log_scales == c.log_scales);
    REQUIRE(r.quats == c.quats);
    REQUIRE(r.opacity_logits == c.opacity_logits);
    REQUIRE(r.sh == c.sh);
  }
}

TEST_CASE("malformed PLY files give errors naming the file", "[export]") {
  TmpDir dir;
  const GaussianCloud c = random_cloud(5, 1, 7);
  const fs::path good = dir / "good.ply";
  write_ply(good, c);
  const auto bytes = read_bytes(good);
  const std::string text(bytes.begin(), bytes.end());
  const size_t data_at = text.find("end_header\n") + 11;

  auto expect_error = [&](const std::string& name, const std::vector<uint8_t>& content, const std::string& what) {
    const fs::path p = dir / name;
    write_bytes(p, content);
    CAPTURE(name);
    REQUIRE_THROWS_AS(read_ply(p), std::runtime_error);
    REQUIRE_THROWS_WITH(read_ply(p), Contains(p.string()) && Contains(what));
  };
  auto edit_header = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const size_t at = t.find(from);
    REQUIRE(at < data_at);
    t.replace(at, from.size(), to);
    return std::vector<uint8_t>(t.begin(), t.end());
  };

  expect_error("truncated.ply", std::vector<uint8_t>(bytes.begin(), bytes.end() - 7), "truncated");
  expect_error("more_vertices.ply", edit_header("element vertex 5", "element vertex 6"), "truncated");
  expect_error("huge_count.ply", edit_header("element vertex 5", "element vertex 99999999999999"), "truncated");
  expect_error("bad_count.ply", edit_header("element vertex 5", "element vertex -5"), "bad count");
  expect_error("garbage_header.ply",
               edit_header("format binary_little_endian 1.0", "format binary_little_endian 1.0\nfoo bar"),
               "unexpected keyword 'foo'");
  expect_error("bad_format.ply", edit_header("binary_little_endian", "binary_middle_endian"), "unknown format");
  expect_error("missing_rot.ply", edit_header("property float rot_3\n", ""), "lacks the required properties: rot_3");
  expect_error("missing_two.ply", edit_header("property float x\nproperty float y\n", ""), "x, y");
  expect_error("rest_count.ply", edit_header("property float f_rest_8\n", ""), "found 8 f_rest_* properties");
  expect_error("rest_gap.ply", edit_header("property float f_rest_8\n", "property float f_rest_9\n"), "f_rest_9");
  expect_error("int_type.ply", edit_header("property float opacity", "property int opacity"), "has type int");
  expect_error("dup.ply", edit_header("property float nx", "property float x"), "duplicate property 'x'");
  expect_error("no_vertex.ply", edit_header("element vertex", "element point"), "no 'vertex' element");
  expect_error("no_end.ply", std::vector<uint8_t>(bytes.begin(), bytes.begin() + data_at - 11), "end_header");
  expect_error("not_ply.ply", std::vector<uint8_t>{'h', 'e', 'l', 'l', 'o', '\n'}, "not a PLY file");
  expect_error("empty.ply", {}, "not a PLY file");
  {
    auto b = bytes;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(b.data() + data_at + (2 * 26 + 9) * 4, &nan, 4);  // vertex 2, f_rest_0 (26 floats a vertex)
    expect_error("nan.ply", b, "vertex 2: property 'f_rest_0' is not a finite float");
  }
  {
    auto b = bytes;
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(b.data() + data_at + (4 * 26 + 18) * 4, &inf, 4);  // vertex 4, opacity
    expect_error("inf.ply", b, "vertex 4: property 'opacity' is not a finite float");
  }
  expect_error("ascii_bad.ply", edit_header("binary_little_endian", "ascii"), "ascii");
  REQUIRE_THROWS_WITH(read_ply(dir / "absent.ply"), Contains((dir / "absent.ply").string()));

  // Random bytes, and random corruptions / truncations of a good file: a clean error or a load,
  // never a crash.
  std::mt19937 rng(3);
  for (int i = 0; i < 300; ++i) {
    std::vector<uint8_t> b;
    if (i < 50) {
      b.resize(rng() % 2000);
      for (auto& x : b) x = uint8_t(rng());
      if (i % 2) b.insert(b.begin(), {'p', 'l', 'y', '\n'});
    } else if (i < 150) {
      b.assign(bytes.begin(), bytes.begin() + rng() % bytes.size());
    } else {
      b = bytes;
      for (int k = 0; k < 4; ++k) b[rng() % b.size()] = uint8_t(rng());
    }
    const fs::path p = dir / "fuzz.ply";
    write_bytes(p, b);
    expect_load_or_clean_error([](const fs::path& q) { return read_ply(q); }, p);
  }
}

// --------------------------------------------------------------------------------------------
// glTF

TEST_CASE("glTF round trip reproduces every parameter after activation, SH degrees 0..3", "[export]") {
  TmpDir dir;
  for (const std::string ext : {".glb", ".gltf"})
    for (int degree = 0; degree <= 3; ++degree) {
      CAPTURE(ext, degree);
      const GaussianCloud c = random_cloud(300, degree, 200 + degree);
      const fs::path p = dir / ("cloud" + std::to_string(degree) + ext);
      GltfExportOptions opt;
      if (degree == 2) opt.color_space = GltfColorSpace::lin_rec709_display;
      if (degree == 1) opt.color_fallback = false;
      write_gltf_splats(p, c, opt);
      GltfColorSpace cs = GltfColorSpace::srgb_rec709_display;
      const GaussianCloud r = read_gltf_splats(p, &cs);
      REQUIRE(cs == opt.color_space);
      REQUIRE(r.sh_degree == degree);
      REQUIRE(r.size() == c.size());
      REQUIRE(r.means == c.means);  // float32 as is
      REQUIRE(r.sh == c.sh);        // float32 as is
      for (size_t g = 0; g < c.size(); ++g) {
        CAPTURE(g);
        for (int a = 0; a < 3; ++a) {
          const double s0 = std::exp(double(c.log_scales[g * 3 + a])), s1 = std::exp(double(r.log_scales[g * 3 + a]));
          REQUIRE(std::fabs(s1 - s0) <= 1e-6 * s0);
          REQUIRE(std::fabs(r.log_scales[g * 3 + a] - c.log_scales[g * 3 + a]) <= 1e-6);
        }
        // Quaternions: the file holds the unit quaternion (same sign).
        double n0 = 0, n1 = 0;
        for (int a = 0; a < 4; ++a) {
          n0 += double(c.quats[g * 4 + a]) * c.quats[g * 4 + a];
          n1 += double(r.quats[g * 4 + a]) * r.quats[g * 4 + a];
        }
        REQUIRE(std::fabs(n1 - 1.0) <= 1e-6);
        for (int a = 0; a < 4; ++a) REQUIRE(std::fabs(r.quats[g * 4 + a] - c.quats[g * 4 + a] / std::sqrt(n0)) <= 1e-6);
        const double x0 = c.opacity_logits[g], x1 = r.opacity_logits[g];
        // Opacity within float rounding; opacities beyond [1e-6, 1 - 1e-6] come back clamped.
        const bool clamped = std::fabs(x0) > std::log((1 - 1e-6) / 1e-6);
        REQUIRE(std::fabs(sigmoid(x1) - sigmoid(x0)) <= (clamped ? 1.0001e-6 : 1e-7));
        if (std::fabs(x0) <= 6)
          REQUIRE(std::fabs(x1 - x0) <= 1e-4);
        else
          REQUIRE(std::fabs(x1 - std::copysign(std::log((1 - 1e-6) / 1e-6), x0)) <= 1e-4);  // clamped
      }
    }
}

TEST_CASE("the glb holds KHR_gaussian_splatting as specified", "[export]") {
  TmpDir dir;
  const GaussianCloud c = random_cloud(40, 3, 9);
  const fs::path p = dir / "splats.glb";
  write_gltf_splats(p, c);
  const auto bytes = read_bytes(p);
  REQUIRE(bytes.size() % 4 == 0);
  uint32_t total;
  std::memcpy(&total, bytes.data() + 8, 4);
  REQUIRE(total == bytes.size());
  const Glb g = split_glb(bytes);
  const json& d = g.doc;
  REQUIRE(d["asset"]["version"] == "2.0");
  REQUIRE(d["asset"]["generator"] == "EvFlow");
  REQUIRE(d["extensionsUsed"] == json::array({"KHR_gaussian_splatting"}));
  REQUIRE_FALSE(d.contains("extensionsRequired"));
  REQUIRE(d["scenes"][0]["nodes"] == json::array({0}));
  REQUIRE(d["meshes"].size() == 1);
  REQUIRE(d["meshes"][0]["primitives"].size() == 1);
  const json& prim = d["meshes"][0]["primitives"][0];
  REQUIRE(prim["mode"] == 0);
  const json& ext = prim["extensions"]["KHR_gaussian_splatting"];
  REQUIRE(ext["kernel"] == "ellipse");
  REQUIRE(ext["colorSpace"] == "srgb_rec709_display");
  const json& attrs = prim["attributes"];
  std::vector<std::string> expected = {"POSITION", "COLOR_0", "KHR_gaussian_splatting:ROTATION",
                                       "KHR_gaussian_splatting:SCALE", "KHR_gaussian_splatting:OPACITY"};
  for (int l = 0; l <= 3; ++l)
    for (int n = 0; n <= 2 * l; ++n)
      expected.push_back("KHR_gaussian_splatting:SH_DEGREE_" + std::to_string(l) + "_COEF_" + std::to_string(n));
  REQUIRE(attrs.size() == expected.size());
  auto accessor_floats = [&](const std::string& semantic) {
    const json& acc = d["accessors"][attrs.at(semantic).get<size_t>()];
    REQUIRE(acc["componentType"] == 5126);
    REQUIRE(acc["count"] == c.size());
    const json& bv = d["bufferViews"][acc["bufferView"].get<size_t>()];
    const size_t comps = acc["type"] == "SCALAR" ? 1 : acc["type"] == "VEC3" ? 3 : 4;
    std::vector<float> v(c.size() * comps);
    REQUIRE(bv["byteLength"].get<size_t>() == v.size() * 4);
    std::memcpy(v.data(), g.bin.data() + bv["byteOffset"].get<size_t>(), v.size() * 4);
    return v;
  };
  for (const auto& name : expected) {
    CAPTURE(name);
    REQUIRE(attrs.contains(name));
    const std::string type = d["accessors"][attrs[name].get<size_t>()]["type"];
    REQUIRE(type == (name == "KHR_gaussian_splatting:OPACITY"                         ? "SCALAR"
                     : name == "COLOR_0" || name == "KHR_gaussian_splatting:ROTATION" ? "VEC4"
                                                                                      : "VEC3"));
  }
  // POSITION min/max are exact.
  const json& pos = d["accessors"][attrs["POSITION"].get<size_t>()];
  for (int a = 0; a < 3; ++a) {
    float lo = 1e30f, hi = -1e30f;
    for (size_t i = 0; i < c.size(); ++i) {
      lo = std::min(lo, c.means[i * 3 + a]);
      hi = std::max(hi, c.means[i * 3 + a]);
    }
    REQUIRE(pos["min"][a].get<float>() == lo);
    REQUIRE(pos["max"][a].get<float>() == hi);
  }
  // Rotation is x y z w; SH coefficient n of degree l is our k = l^2 + n; COLOR_0 is the sRGB-decoded
  // DC colour with alpha = opacity.
  const auto rot = accessor_floats("KHR_gaussian_splatting:ROTATION");
  const auto sh21 = accessor_floats("KHR_gaussian_splatting:SH_DEGREE_2_COEF_1");
  const auto color = accessor_floats("COLOR_0");
  const auto opacity = accessor_floats("KHR_gaussian_splatting:OPACITY");
  const auto scale = accessor_floats("KHR_gaussian_splatting:SCALE");
  for (size_t i = 0; i < c.size(); ++i) {
    const float* q = &c.quats[i * 4];
    const double n = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
    REQUIRE(rot[i * 4 + 3] == Approx(q[0] / n).margin(1e-7));
    REQUIRE(rot[i * 4 + 0] == Approx(q[1] / n).margin(1e-7));
    for (int ch = 0; ch < 3; ++ch) {
      REQUIRE(sh21[i * 3 + ch] == c.sh[(i * 16 + 5) * 3 + ch]);
      const double srgb = std::clamp(0.28209479177387814 * c.sh[i * 16 * 3 + ch] + 0.5, 0.0, 1.0);
      const double lin = reference::srgb_decode(srgb);
      REQUIRE(color[i * 4 + ch] == Approx(lin).margin(1e-6));
      REQUIRE(scale[i * 3 + ch] == Approx(std::exp(double(c.log_scales[i * 3 + ch]))).epsilon(1e-6));
    }
    REQUIRE(opacity[i] == Approx(sigmoid(c.opacity_logits[i])).margin(1e-7));
    REQUIRE(color[i * 4 + 3] == opacity[i]);
  }
}

TEST_CASE("glTF import accepts other tools' encodings", "[export]") {
  TmpDir dir;
  const GaussianCloud c = random_cloud(6, 1, 21);
  const fs::path p = dir / "a.glb";
  write_gltf_splats(p, c, {GltfColorSpace::srgb_rec709_display, false});
  Glb g = split_glb(read_bytes(p));
  json& d = g.doc;
  json& attrs = d["meshes"][0]["primitives"][0]["attributes"];

  // Quantised rotation (normalized short), scale (unsigned byte, not normalized) and opacity
  // (normalized unsigned byte), appended as one interleaved bufferView: 8 + 3 + 1 bytes, stride 12.
  const size_t n = c.size();
  const size_t at = g.bin.size();
  g.bin.resize(at + n * 12);
  for (size_t i = 0; i < n; ++i) {
    uint8_t* e = g.bin.data() + at + i * 12;
    const int16_t q[4] = {0, 0, int16_t(-32767), 0};  // (x, y, z, w) = (0, 0, -1, 0)
    std::memcpy(e, q, 8);
    e[8] = uint8_t(i + 1);
    e[9] = 2;
    e[10] = 3;
    e[11] = uint8_t(51 * (i % 6));  // opacity i/5 for i < 6, 0 and 1 included
  }
  d["buffers"][0]["byteLength"] = g.bin.size();
  const size_t bv = d["bufferViews"].size();
  d["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", n * 12}, {"byteStride", 12}});
  const size_t acc = d["accessors"].size();
  d["accessors"].push_back(
      {{"bufferView", bv}, {"componentType", 5122}, {"normalized", true}, {"count", n}, {"type", "VEC4"}});
  d["accessors"].push_back(
      {{"bufferView", bv}, {"byteOffset", 8}, {"componentType", 5121}, {"count", n}, {"type", "VEC3"}});
  d["accessors"].push_back({{"bufferView", bv},
                            {"byteOffset", 11},
                            {"componentType", 5121},
                            {"normalized", true},
                            {"count", n},
                            {"type", "SCALAR"}});
  attrs["KHR_gaussian_splatting:ROTATION"] = acc;
  attrs["KHR_gaussian_splatting:SCALE"] = acc + 1;
  attrs["KHR_gaussian_splatting:OPACITY"] = acc + 2;
  // A second splat primitive of SH degree 0 (sharing POSITION and DC) is appended to the cloud.
  json second = d["meshes"][0]["primitives"][0];
  for (int k = 0; k < 3; ++k)
    second["attributes"].erase("KHR_gaussian_splatting:SH_DEGREE_1_COEF_" + std::to_string(k));
  d["meshes"].push_back({{"primitives", json::array({second})}});
  const fs::path q = dir / "b.glb";
  write_bytes(q, join_glb(g));

  const GaussianCloud r = read_gltf_splats(q);
  REQUIRE(r.size() == 2 * n);
  REQUIRE(r.sh_degree == 1);
  for (size_t j = 0; j < 2 * n; ++j) {
    const size_t i = j % n;
    CAPTURE(j);
    REQUIRE(r.means[j * 3] == c.means[i * 3]);
    REQUIRE(r.quats[j * 4 + 0] == 0.0f);   // w
    REQUIRE(r.quats[j * 4 + 3] == -1.0f);  // z
    REQUIRE(std::exp(r.log_scales[j * 3 + 0]) == Approx(double(i + 1)).epsilon(1e-6));
    REQUIRE(std::exp(r.log_scales[j * 3 + 2]) == Approx(3.0).epsilon(1e-6));
    const double o = std::clamp(double(i % 6) / 5.0, 1e-6, 1 - 1e-6);
    REQUIRE(r.opacity_logits[j] == Approx(std::log(o / (1 - o))).margin(1e-4));
    for (int ch = 0; ch < 3; ++ch) REQUIRE(r.sh[(j * 4 + 0) * 3 + ch] == c.sh[(i * 4 + 0) * 3 + ch]);
    for (int k = 1; k < 4; ++k)
      for (int ch = 0; ch < 3; ++ch) REQUIRE(r.sh[(j * 4 + k) * 3 + ch] == (j < n ? c.sh[(i * 4 + k) * 3 + ch] : 0.0f));
  }

  // .gltf with an external .bin next to it.
  json ext_doc = d;
  ext_doc["buffers"][0]["uri"] = "b%20data.bin";  // percent-encoded relative URI
  write_text(dir / "c.gltf", ext_doc.dump(2));
  write_bytes(dir / "b data.bin", g.bin);
  REQUIRE(read_gltf_splats(dir / "c.gltf").means == r.means);
}

TEST_CASE("malformed glTF files give errors naming the file", "[export]") {
  TmpDir dir;
  const GaussianCloud c = random_cloud(8, 2, 31);
  const fs::path good = dir / "good.glb";
  write_gltf_splats(good, c);
  const auto bytes = read_bytes(good);
  const Glb base = split_glb(bytes);

  auto expect_error = [&](const std::string& name, const std::vector<uint8_t>& content, const std::string& what) {
    const fs::path p = dir / name;
    write_bytes(p, content);
    CAPTURE(name);
    REQUIRE_THROWS_AS(read_gltf_splats(p), std::runtime_error);
    REQUIRE_THROWS_WITH(read_gltf_splats(p), Contains(p.string()) && Contains(what));
  };
  auto tampered = [&](const std::function<void(Glb&)>& edit) {
    Glb g = base;
    edit(g);
    return join_glb(g);
  };
  auto attrs_of = [](Glb& g) -> json& { return g.doc["meshes"][0]["primitives"][0]["attributes"]; };

  expect_error("truncated.glb", std::vector<uint8_t>(bytes.begin(), bytes.end() - 5), "truncated");
  expect_error("short.glb", std::vector<uint8_t>(bytes.begin(), bytes.begin() + 10), "truncated");
  expect_error("random.glb", std::vector<uint8_t>{1, 2, 3, 4, 5, 6, 7, 8, 9}, "not a glTF file");
  expect_error("empty.glb", {}, "not a glTF file");
  expect_error(
      "version.glb",
      [&] {
        auto b = bytes;
        b[4] = 1;
        return b;
      }(),
      "GLB version 1");
  expect_error(
      "bad_json.glb",
      [&] {
        auto b = bytes;
        b[20] = '#';
        return b;
      }(),
      "not valid JSON");
  expect_error("plain_mesh.glb", tampered([&](Glb& g) { g.doc["meshes"][0]["primitives"][0].erase("extensions"); }),
               "no mesh primitive carries KHR_gaussian_splatting");
  expect_error("no_meshes.glb", tampered([&](Glb& g) { g.doc.erase("meshes"); }), "no mesh primitive");
  expect_error("missing_scale.glb", tampered([&](Glb& g) { attrs_of(g).erase("KHR_gaussian_splatting:SCALE"); }),
               "lacks the required attribute KHR_gaussian_splatting:SCALE");
  expect_error("missing_dc.glb",
               tampered([&](Glb& g) { attrs_of(g).erase("KHR_gaussian_splatting:SH_DEGREE_0_COEF_0"); }),
               "SH_DEGREE_0_COEF_0");
  expect_error("partial_sh.glb",
               tampered([&](Glb& g) { attrs_of(g).erase("KHR_gaussian_splatting:SH_DEGREE_2_COEF_3"); }),
               "SH degree 2 is partially defined (4 of 5");
  expect_error("sh_gap.glb", tampered([&](Glb& g) {
                 for (int k = 0; k < 3; ++k)
                   attrs_of(g).erase("KHR_gaussian_splatting:SH_DEGREE_1_COEF_" + std::to_string(k));
               }),
               "SH degree 2 is present but degree 1 is not");
  expect_error("bad_sh_name.glb",
               tampered([&](Glb& g) { attrs_of(g)["KHR_gaussian_splatting:SH_DEGREE_1_COEF_5"] = 0; }),
               "malformed SH attribute 'KHR_gaussian_splatting:SH_DEGREE_1_COEF_5'");
  expect_error("sh_degree4.glb",
               tampered([&](Glb& g) { attrs_of(g)["KHR_gaussian_splatting:SH_DEGREE_4_COEF_0"] = 0; }), "SH degree 4");
  expect_error("bad_index.glb", tampered([&](Glb& g) { attrs_of(g)["KHR_gaussian_splatting:OPACITY"] = 999; }),
               "accessors[999], which does not exist");
  expect_error("bad_type.glb", tampered([&](Glb& g) {
                 g.doc["accessors"][attrs_of(g)["KHR_gaussian_splatting:SCALE"].get<int>()]["type"] = "VEC4";
               }),
               "expected VEC3");
  expect_error("count.glb", tampered([&](Glb& g) {
                 g.doc["accessors"][attrs_of(g)["KHR_gaussian_splatting:OPACITY"].get<int>()]["count"] = 7;
               }),
               "has 7 elements but POSITION has 8");
  expect_error("overrun.glb", tampered([&](Glb& g) {
                 g.doc["accessors"][attrs_of(g)["KHR_gaussian_splatting:OPACITY"].get<int>()]["count"] = 100000;
               }),
               "does not fit in bufferViews");
  expect_error("view_overrun.glb", tampered([&](Glb& g) { g.doc["bufferViews"][3]["byteOffset"] = 1u << 31; }),
               "runs past the end of buffers[0]");
  expect_error("short_bin.glb", tampered([&](Glb& g) { g.bin.resize(g.bin.size() - 64); }), "truncated");
  expect_error(
      "nan.glb", tampered([&](Glb& g) {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const size_t off =
            g.doc["bufferViews"][attrs_of(g)["KHR_gaussian_splatting:SH_DEGREE_1_COEF_2"].get<int>()]["byteOffset"];
        std::memcpy(g.bin.data() + off + 4, &nan, 4);
      }),
      "element 0 component 1 is not finite");
  expect_error("neg_scale.glb", tampered([&](Glb& g) {
                 const float neg = -1.0f;
                 const size_t off =
                     g.doc["bufferViews"][attrs_of(g)["KHR_gaussian_splatting:SCALE"].get<int>()]["byteOffset"];
                 std::memcpy(g.bin.data() + off, &neg, 4);
               }),
               "negative");
  expect_error("kernel.glb", tampered([&](Glb& g) {
                 g.doc["meshes"][0]["primitives"][0]["extensions"]["KHR_gaussian_splatting"]["kernel"] = "cube";
               }),
               "reads only \"ellipse\"");
  expect_error("mode.glb", tampered([&](Glb& g) { g.doc["meshes"][0]["primitives"][0].erase("mode"); }), "has mode 4");
  expect_error("required.glb",
               tampered([&](Glb& g) { g.doc["extensionsRequired"] = {"KHR_spz_gaussian_splats_compression"}; }),
               "requires extension");
  expect_error("not_gltf.gltf", std::vector<uint8_t>{'{', '"', 'a', '"', ':', '1', '}'}, "lacks 'asset'");
  expect_error(
      "bad_b64.gltf",
      [&] {
        json d = base.doc;
        d["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@";
        const std::string s = d.dump();
        return std::vector<uint8_t>(s.begin(), s.end());
      }(),
      "invalid base64");
  expect_error(
      "missing_bin.gltf",
      [&] {
        json d = base.doc;
        d["buffers"][0]["uri"] = "nowhere.bin";
        const std::string s = d.dump();
        return std::vector<uint8_t>(s.begin(), s.end());
      }(),
      "cannot open external buffer");
  REQUIRE_THROWS_WITH(read_gltf_splats(dir / "absent.glb"), Contains((dir / "absent.glb").string()));

  // Random corruptions and truncations: a clean error or a load, never a crash.
  std::mt19937 rng(5);
  for (int i = 0; i < 300; ++i) {
    std::vector<uint8_t> b;
    if (i < 100)
      b.assign(bytes.begin(), bytes.begin() + rng() % bytes.size());
    else {
      b = bytes;
      for (int k = 0; k < 3; ++k) b[rng() % b.size()] = uint8_t(rng());
    }
    const fs::path p = dir / "fuzz.glb";
    write_bytes(p, b);
    expect_load_or_clean_error([](const fs::path& q) { return read_gltf_splats(q); }, p);
  }
}

// --------------------------------------------------------------------------------------------
// Writes are atomic

TEST_CASE("a failing export leaves the existing file untouched", "[export]") {
  TmpDir dir;
  const GaussianCloud good = random_cloud(10, 1, 41);
  GaussianCloud bad = good;
  bad.means[4] = std::numeric_limits<float>::quiet_NaN();
  GaussianCloud huge = good;
  huge.log_scales[7] = 200.0f;  // exp() overflows float: valid PLY, impossible glTF

  const fs::path ply = dir / "out.ply", glb = dir / "out.glb", gltf = dir / "out.gltf";
  write_ply(ply, good);
  write_gltf_splats(glb, good);
  write_gltf_splats(gltf, good);
  const auto ply_before = read_bytes(ply), glb_before = read_bytes(glb), gltf_before = read_bytes(gltf);

  REQUIRE_THROWS_AS(write_ply(ply, bad), std::invalid_argument);
  REQUIRE_THROWS_WITH(write_ply(ply, bad), Contains(ply.string()) && Contains("not finite"));
  REQUIRE_THROWS_AS(write_gltf_splats(glb, bad), std::invalid_argument);
  REQUIRE_THROWS_WITH(write_gltf_splats(glb, huge), Contains(glb.string()) && Contains("overflows float"));
  REQUIRE_THROWS_WITH(write_gltf_splats(gltf, huge), Contains("overflows float"));
  GaussianCloud empty;
  empty.resize(0, 0);
  REQUIRE_THROWS_WITH(write_gltf_splats(glb, empty), Contains("empty cloud"));
  REQUIRE_THROWS_WITH(write_gltf_splats(dir / "out.obj", good), Contains("use .glb or .gltf"));

  REQUIRE(read_bytes(ply) == ply_before);
  REQUIRE(read_bytes(glb) == glb_before);
  REQUIRE(read_bytes(gltf) == gltf_before);
  REQUIRE(read_ply(ply).means == good.means);
  REQUIRE(read_gltf_splats(glb).means == good.means);
  // No temporaries left behind.
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path)) ++files;
  REQUIRE(files == 3);
  // A successful overwrite replaces the content.
  write_ply(ply, random_cloud(3, 0, 1));
  REQUIRE(read_ply(ply).size() == 3);
}

// --------------------------------------------------------------------------------------------
// Khronos glTF validator

TEST_CASE("the Khronos glTF validator accepts our glb", "[export][gltf-validator]") {
  const char* script = std::getenv("EVF_GLTF_VALIDATOR");
  if (!script || !*script)
    FAIL(
        "EVF_GLTF_VALIDATOR is not set. Set it up with:\n"
        "  (cd tests/tools && npm ci)\n"
        "  export EVF_GLTF_VALIDATOR=$PWD/tests/tools/validate_gltf.mjs\n"
        "(needs node >= 18; see docs/export.md)");
  REQUIRE(fs::is_regular_file(script));
  TmpDir dir;
  for (const std::string name : {"splats.glb", "splats.gltf"}) {
    const fs::path p = dir / name;
    write_gltf_splats(p, random_cloud(500, 3, 51));
    const fs::path log = dir / (name + ".log");
    const std::string cmd = "node '" + std::string(script) + "' '" + p.string() + "' > '" + log.string() + "' 2>&1";
    const int status = std::system(cmd.c_str());
    const auto out = read_bytes(log);
    const std::string output(out.begin(), out.end());
    INFO(cmd << "\n" << output);
    REQUIRE(status != -1);
    REQUIRE(WIFEXITED(status));
    REQUIRE(WEXITSTATUS(status) == 0);
    REQUIRE_THAT(output, Contains(" 0 errors"));
  }
}

// Splat colours are display-referred sRGB, as in every 3DGS tool: a PLY written by another tool
// renders the bytes that tool shows (3DGS's image formation: colour = 0.5 + C0 f_dc, alpha
// capped at 0.99, blended as they are, no transfer function), and the glb EvFlow exports from it
// says srgb_rec709_display and renders the same.
TEST_CASE("an Inria PLY from another tool renders its own colours (sRGB splats), through PLY and glTF",
          "[export][gpu]") {
  TmpDir dir;
  const double c0 = 0.28209479177387814;
  const double colour[3] = {0.2, 0.5, 0.8};
  std::string ply = "ply\nformat ascii 1.0\nelement vertex 1\n";
  for (const char* p : {"x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
                        "rot_0", "rot_1", "rot_2", "rot_3"})
    ply += std::string("property float ") + p + "\n";
  char body[256];
  std::snprintf(body, sizeof body, "end_header\n0 0 5 %.9g %.9g %.9g 10 0 0 0 1 0 0 0\n", (colour[0] - 0.5) / c0,
                (colour[1] - 0.5) / c0, (colour[2] - 0.5) / c0);
  ply += body;
  write_bytes(dir / "other.ply", std::vector<uint8_t>(ply.begin(), ply.end()));
  const GaussianCloud cloud = read_ply(dir / "other.ply");
  write_gltf_splats(dir / "other.glb", cloud, GltfExportOptions{});
  GltfColorSpace space = GltfColorSpace::lin_rec709_display;
  const GaussianCloud via_glb = read_gltf_splats(dir / "other.glb", &space);
  CHECK(space == GltfColorSpace::srgb_rec709_display);

  auto& ctx = test::gpu_context();
  const uint32_t W = 64, H = 48;
  const Camera cam = Camera::look_at(W, H, 60.0, {0, 0, 0}, {0, 0, 5}, {0, -1, 0});
  for (const GaussianCloud* c : {&cloud, &via_glb}) {
    GaussianBuffers params(ctx, c->size(), c->sh_degree, "other_");
    params.upload(*c);
    Rasterizer r(ctx);
    RenderState rs(ctx);
    r.forward(params, cam, RenderSettings{}, rs);
    const std::vector<float> img = rs.outputs().rgb.read<float>(size_t(3) * W * H);
    // The centre pixels: alpha = min(0.99, sigmoid(10) exp(-q/2)) = 0.99 over a black background.
    for (uint32_t y : {H / 2 - 1, H / 2})
      for (uint32_t x : {W / 2 - 1, W / 2})
        for (int ch = 0; ch < 3; ++ch) {
          const int want = int(std::lround(0.99 * colour[ch] * 255.0));
          const int got = test::quantise8(img[size_t(ch) * W * H + size_t(y) * W + x]);
          CAPTURE(x, y, ch);
          CHECK(std::abs(got - want) <= 1);
        }
  }
  test::require_no_validation_messages();
}
