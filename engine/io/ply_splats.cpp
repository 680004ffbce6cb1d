#include "io/ply_splats.h"

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/atomic_file.h"

namespace evflow::io {

namespace fs = std::filesystem;
static_assert(std::endian::native == std::endian::little, "PLY I/O assumes a little-endian host");

namespace {

// ---------------------------------------------------------------------------------------------
// Writing

void write_ply_file(const fs::path& tmp, const fs::path& target, const GaussianCloud& cloud) {
  const size_t n = cloud.size();
  const int K = cloud.coeffs();
  const int rest = 3 * (K - 1);  // f_rest count: 0, 9, 24, 45

  std::string header = "ply\nformat binary_little_endian 1.0\n";
  header += "comment EvFlow 3D Gaussian splats, Inria layout, SH degree " + std::to_string(cloud.sh_degree) + "\n";
  header += "element vertex " + std::to_string(n) + "\n";
  for (const char* name : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    header += std::string("property float ") + name + "\n";
  for (int i = 0; i < rest; ++i) header += "property float f_rest_" + std::to_string(i) + "\n";
  for (const char* name : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    header += std::string("property float ") + name + "\n";
  header += "end_header\n";

  const size_t per = 17 + static_cast<size_t>(rest);
  std::vector<float> row(per);
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(tmp.string() + ": cannot open for writing");
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  // Rows are written in batches so that a large cloud does not need a second full copy.
  constexpr size_t kBatch = 4096;
  std::vector<float> batch;
  batch.reserve(kBatch * per);
  for (size_t g = 0; g < n; ++g) {
    float* r = row.data();
    for (int a = 0; a < 3; ++a) r[a] = cloud.means[g * 3 + a];
    r[3] = r[4] = r[5] = 0.0f;  // normals: unused by splats, zero like the Inria code
    const float* sh = &cloud.sh[g * K * 3];
    for (int c = 0; c < 3; ++c) r[6 + c] = sh[c];  // DC, k = 0
    for (int c = 0; c < 3; ++c)                    // channel-major rest
      for (int k = 1; k < K; ++k) r[9 + c * (K - 1) + (k - 1)] = sh[k * 3 + c];
    float* tail = r + 9 + rest;
    tail[0] = cloud.opacity_logits[g];
    for (int a = 0; a < 3; ++a) tail[1 + a] = cloud.log_scales[g * 3 + a];
    for (int a = 0; a < 4; ++a) tail[4 + a] = cloud.quats[g * 4 + a];
    batch.insert(batch.end(), row.begin(), row.end());
    if (batch.size() >= kBatch * per || g + 1 == n) {
      out.write(reinterpret_cast<const char*>(batch.data()),
                static_cast<std::streamsize>(batch.size() * sizeof(float)));
      batch.clear();
    }
  }
  close_or_throw(out, target);
}

// ---------------------------------------------------------------------------------------------
// Reading

// Thrown inside the parser; read_ply() prefixes the file name.
struct PlyError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class PType { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<PType> parse_type(std::string_view s) {
  if (s == "char" || s == "int8") return PType::i8;
  if (s == "uchar" || s == "uint8") return PType::u8;
  if (s == "short" || s == "int16") return PType::i16;
  if (s == "ushort" || s == "uint16") return PType::u16;
  if (s == "int" || s == "int32") return PType::i32;
  if (s == "uint" || s == "uint32") return PType::u32;
  if (s == "float" || s == "float32") return PType::f32;
  if (s == "double" || s == "float64") return PType::f64;
  return std::nullopt;
}

size_t type_size(PType t) {
  switch (t) {
    case PType::i8:
    case PType::u8:
      return 1;
    case PType::i16:
    case PType::u16:
      return 2;
    case PType::i32:
    case PType::u32:
    case PType::f32:
      return 4;
    case PType::f64:
      return 8;
  }
  return 0;
}

const char* type_name(PType t) {
  switch (t) {
    case PType::i8:
      return "char";
    case PType::u8:
      return "uchar";
    case PType::i16:
      return "short";
    case PType::u16:
      return "ushort";
    case PType::i32:
      return "int";
    case PType::u32:
      return "uint";
    case PType::f32:
      return "float";
    case PType::f64:
      return "double";
  }
  return "?";
}

struct Property {
  std::string name;
  PType type = PType::f32;
  bool is_list = false;
  PType count_type = PType::u8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
};

enum class Format { ascii, binary_le, binary_be };

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// Sequential reader of element data, bounds-checked; values come back as double.
class DataReader {
 public:
  DataReader(const uint8_t* data, size_t size, Format format) : data_(data), size_(size), format_(format) {}

  size_t remaining() const { return size_ - pos_; }

  double read(PType t) { return format_ == Format::ascii ? read_ascii() : read_binary(t); }

  void skip_bytes(uint64_t bytes) {
    if (bytes > remaining()) throw PlyError("truncated data while skipping an element");
    pos_ += static_cast<size_t>(bytes);
  }

 private:
  double read_binary(PType t) {
    const size_t s = type_size(t);
    if (s > remaining())
      throw PlyError("truncated data: needed " + std::to_string(s) + " more bytes at offset " + std::to_string(pos_));
    uint8_t b[8];
    std::memcpy(b, data_ + pos_, s);
    pos_ += s;
    if (format_ == Format::binary_be)
      for (size_t i = 0; i < s / 2; ++i) std::swap(b[i], b[s - 1 - i]);
    switch (t) {
      case PType::i8: {
        int8_t v;
        std::memcpy(&v, b, 1);
        return v;
      }
      case PType::u8:
        return b[0];
      case PType::i16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PType::u16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PType::i32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PType::u32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PType::f32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PType::f64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    }
    return 0;
  }

  double read_ascii() {
    while (pos_ < size_ && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ >= size_) throw PlyError("truncated ascii data: expected more values");
    const size_t start = pos_;
    while (pos_ < size_ && !std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    const char* first = reinterpret_cast<const char*>(data_ + start);
    const char* last = reinterpret_cast<const char*>(data_ + pos_);
    if (*first == '+') ++first;  // from_chars rejects a leading '+'
    double v = 0;
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (ec == std::errc::result_out_of_range) return std::numeric_limits<double>::infinity();  // caught as non-finite
    if (ec != std::errc() || ptr != last)
      throw PlyError("bad ascii value '" +
                     std::string(reinterpret_cast<const char*>(data_ + start), std::min<size_t>(pos_ - start, 40)) +
                     "' at offset " + std::to_string(start));
    return v;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  Format format_;
};

struct Header {
  Format format = Format::binary_le;
  std::vector<Element> elements;
  size_t data_offset = 0;
};

Header parse_header(const std::vector<uint8_t>& bytes) {
  Header h;
  const std::string_view all(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  size_t pos = 0;
  int line_no = 0;
  bool have_format = false, ended = false;
  auto next_line = [&]() -> std::optional<std::string_view> {
    if (pos >= all.size()) return std::nullopt;
    size_t end = all.find('\n', pos);
    if (end == std::string_view::npos) end = all.size();
    std::string_view line = all.substr(pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_no;
    return line;
  };
  auto first = next_line();
  if (!first || *first != "ply") throw PlyError("not a PLY file (it does not start with the line 'ply')");
  while (auto line = next_line()) {
    if (line->size() > 4096)
      throw PlyError("header line " + std::to_string(line_no) + " is too long (binary data without end_header?)");
    const auto w = split_words(*line);
    const std::string at = "header line " + std::to_string(line_no) + ": ";
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
      break;
    }
    if (w[0] == "format") {
      if (w.size() != 3) throw PlyError(at + "malformed format line");
      if (w[1] == "ascii")
        h.format = Format::ascii;
      else if (w[1] == "binary_little_endian")
        h.format = Format::binary_le;
      else if (w[1] == "binary_big_endian")
        h.format = Format::binary_be;
      else
        throw PlyError(at + "unknown format '" + std::string(w[1]) + "'");
      if (w[2] != "1.0") throw PlyError(at + "unsupported PLY version '" + std::string(w[2]) + "'");
      have_format = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) throw PlyError(at + "malformed element line");
      Element e;
      e.name = std::string(w[1]);
      const auto [ptr, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (ec != std::errc() || ptr != w[2].data() + w[2].size())
        throw PlyError(at + "bad count '" + std::string(w[2]) + "' for element '" + e.name + "'");
      h.elements.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (h.elements.empty()) throw PlyError(at + "property before any element");
      Property p;
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) throw PlyError(at + "malformed list property line");
        const auto ct = parse_type(w[2]), vt = parse_type(w[3]);
        if (!ct || !vt) throw PlyError(at + "unknown property type");
        if (*ct == PType::f32 || *ct == PType::f64) throw PlyError(at + "list count type must be an integer");
        p.is_list = true;
        p.count_type = *ct;
        p.type = *vt;
        p.name = std::string(w[4]);
      } else {
        if (w.size() != 3) throw PlyError(at + "malformed property line");
        const auto t = parse_type(w[1]);
        if (!t) throw PlyError(at + "unknown property type '" + std::string(w[1]) + "'");
        p.type = *t;
        p.name = std::string(w[2]);
      }
      for (const auto& q : h.elements.back().props)
        if (q.name == p.name)
          throw PlyError(at + "duplicate property '" + p.name + "' in element '" + h.elements.back().name + "'");
      h.elements.back().props.push_back(std::move(p));
    } else {
      throw PlyError(at + "unexpected keyword '" + std::string(w[0].substr(0, 40)) + "'");
    }
  }
  if (!ended) throw PlyError("header has no end_header line (truncated or not a PLY file)");
  if (!have_format) throw PlyError("header has no format line");
  h.data_offset = pos;
  return h;
}

// Slots of one vertex's values that we keep.
enum Slot : int { kX = 0, kDc = 3, kOpacity = 6, kScale = 7, kRot = 10, kRest = 14 };

void read_element_item(DataReader& r, const Element& e) {
  for (const auto& p : e.props) {
    if (!p.is_list) {
      r.read(p.type);
      continue;
    }
    const double cnt = r.read(p.count_type);
    if (!(cnt >= 0) || cnt > 1e9) throw PlyError("bad list length in element '" + e.name + "'");
    for (uint64_t i = 0; i < static_cast<uint64_t>(cnt); ++i) r.read(p.type);
  }
}

const char* const kFixedNames[kRest] = {"x",       "y",       "z",       "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
                                        "scale_0", "scale_1", "scale_2", "rot_0",  "rot_1",  "rot_2",  "rot_3"};

size_t vertex_element(const Header& h) {
  for (size_t i = 0; i < h.elements.size(); ++i)
    if (h.elements[i].name == "vertex") return i;
  throw PlyError("no 'vertex' element in the header");
}

// The slot of f_rest_<k>, checked to be one of rest_count coefficients.
int rest_slot(const std::string& name, int rest_count) {
  const std::string_view idx = std::string_view(name).substr(7);
  int k = -1;
  const auto [ptr, ec] = std::from_chars(idx.data(), idx.data() + idx.size(), k);
  if (ec != std::errc() || ptr != idx.data() + idx.size() || k < 0 || k >= rest_count ||
      (idx.size() > 1 && idx[0] == '0'))
    throw PlyError("property '" + name + "' does not fit f_rest_0..f_rest_" + std::to_string(rest_count - 1));
  return kRest + k;
}

// The vertex properties mapped onto slots (-1: ignored, e.g. nx or red).
struct VertexSlots {
  std::vector<int> slot_of;
  int rest_count = 0;
};

VertexSlots map_slots(const Element& ve) {
  VertexSlots m;
  m.slot_of.assign(ve.props.size(), -1);
  for (const auto& p : ve.props)
    if (p.name.rfind("f_rest_", 0) == 0) ++m.rest_count;
  if (m.rest_count != 0 && m.rest_count != 9 && m.rest_count != 24 && m.rest_count != 45)
    throw PlyError("found " + std::to_string(m.rest_count) +
                   " f_rest_* properties; expected 0, 9, 24 or 45 (SH degree 0..3)");
  bool fixed_seen[kRest] = {};
  for (size_t i = 0; i < ve.props.size(); ++i) {
    const Property& p = ve.props[i];
    int slot = -1;
    for (int s = 0; s < kRest; ++s)
      if (p.name == kFixedNames[s]) slot = s;
    if (slot < 0 && p.name.rfind("f_rest_", 0) == 0) slot = rest_slot(p.name, m.rest_count);
    if (slot < 0) continue;
    if (slot < kRest) fixed_seen[slot] = true;
    if (p.is_list) throw PlyError("property '" + p.name + "' is a list; expected a float or double scalar");
    if (p.type != PType::f32 && p.type != PType::f64)
      throw PlyError("property '" + p.name + "' has type " + type_name(p.type) + "; expected float or double");
    m.slot_of[i] = slot;
  }
  std::string missing;
  for (int s = 0; s < kRest; ++s)
    if (!fixed_seen[s]) missing += std::string(missing.empty() ? "" : ", ") + kFixedNames[s];
  if (!missing.empty()) throw PlyError("vertex element lacks the required properties: " + missing);
  // (the rest slots are complete: rest_count distinct indices in [0, rest_count) were found.)
  return m;
}

// Skips the data of the elements before element `vi`.
void skip_elements(DataReader& r, const Header& h, size_t vi) {
  for (size_t i = 0; i < vi; ++i) {
    const Element& e = h.elements[i];
    if (e.props.empty()) continue;
    bool fixed = h.format != Format::ascii;
    uint64_t stride = 0;
    for (const auto& p : e.props) {
      fixed = fixed && !p.is_list;
      stride += type_size(p.type);
    }
    if (fixed) {
      if (stride != 0 && e.count > r.remaining() / stride)
        throw PlyError("truncated data in element '" + e.name + "' before the vertices");
      r.skip_bytes(e.count * stride);
    } else {
      if (e.count > r.remaining()) throw PlyError("truncated data in element '" + e.name + "' before the vertices");
      for (uint64_t j = 0; j < e.count; ++j) read_element_item(r, e);
    }
  }
}

// Bounds the vertex count by the data left, before anything is allocated.
void check_vertex_bytes(const DataReader& r, const Header& h, const Element& ve) {
  uint64_t min_bytes_per_vertex = 0;
  for (const auto& p : ve.props)
    min_bytes_per_vertex += h.format == Format::ascii ? 1 : type_size(p.is_list ? p.count_type : p.type);
  if (min_bytes_per_vertex == 0 || ve.count > r.remaining() / min_bytes_per_vertex)
    throw PlyError("truncated data: the header declares " + std::to_string(ve.count) + " vertices of " +
                   std::to_string(ve.props.size()) + " properties but only " + std::to_string(r.remaining()) +
                   " bytes of data follow");
}

// Vertex g's kept values, by slot.
void read_vertex(DataReader& r, const Element& ve, const VertexSlots& m, uint64_t g, std::vector<double>& v) {
  for (size_t i = 0; i < ve.props.size(); ++i) {
    const Property& p = ve.props[i];
    if (p.is_list) {
      const double cnt = r.read(p.count_type);
      if (!(cnt >= 0) || cnt > 1e9) throw PlyError("bad list length in vertex " + std::to_string(g));
      for (uint64_t j = 0; j < static_cast<uint64_t>(cnt); ++j) r.read(p.type);
      continue;
    }
    const double x = r.read(p.type);
    if (m.slot_of[i] < 0) continue;
    if (!std::isfinite(x) || std::fabs(x) > std::numeric_limits<float>::max())
      throw PlyError("vertex " + std::to_string(g) + ": property '" + p.name + "' is not a finite float (" +
                     std::to_string(x) + ")");
    v[m.slot_of[i]] = x;
  }
}

void store_vertex(GaussianCloud& cloud, size_t g, int K, const std::vector<double>& v) {
  for (int a = 0; a < 3; ++a) cloud.means[g * 3 + a] = static_cast<float>(v[kX + a]);
  float* sh = &cloud.sh[g * K * 3];
  for (int c = 0; c < 3; ++c) sh[c] = static_cast<float>(v[kDc + c]);
  for (int c = 0; c < 3; ++c)
    for (int k = 1; k < K; ++k) sh[k * 3 + c] = static_cast<float>(v[kRest + c * (K - 1) + (k - 1)]);
  cloud.opacity_logits[g] = static_cast<float>(v[kOpacity]);
  for (int a = 0; a < 3; ++a) cloud.log_scales[g * 3 + a] = static_cast<float>(v[kScale + a]);
  for (int a = 0; a < 4; ++a) cloud.quats[g * 4 + a] = static_cast<float>(v[kRot + a]);
}

GaussianCloud parse_ply(const std::vector<uint8_t>& bytes) {
  const Header h = parse_header(bytes);
  DataReader r(bytes.data() + h.data_offset, bytes.size() - h.data_offset, h.format);
  const size_t vi = vertex_element(h);
  const Element& ve = h.elements[vi];
  const VertexSlots m = map_slots(ve);
  skip_elements(r, h, vi);
  check_vertex_bytes(r, h, ve);
  const int degree = m.rest_count == 0 ? 0 : m.rest_count == 9 ? 1 : m.rest_count == 24 ? 2 : 3;
  const int K = sh_coeff_count(degree);
  GaussianCloud cloud;
  cloud.resize(static_cast<size_t>(ve.count), degree);
  std::vector<double> v(kRest + m.rest_count);
  for (uint64_t g = 0; g < ve.count; ++g) {
    read_vertex(r, ve, m, g, v);
    store_vertex(cloud, static_cast<size_t>(g), K, v);
  }
  return cloud;
}

}  // namespace

void write_ply(const fs::path& path, const GaussianCloud& cloud) {
  cloud.validate(path.string());
  write_file_atomic(path, [&](const fs::path& tmp) { write_ply_file(tmp, path, cloud); });
}

GaussianCloud read_ply(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open PLY file");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path.string() + ": read error");
  try {
    return parse_ply(bytes);
  } catch (const PlyError& e) {
    throw std::runtime_error(path.string() + ": " + e.what());
  } catch (const std::bad_alloc&) { throw std::runtime_error(path.string() + ": PLY too large to load"); }
}

}  // namespace evflow::io
