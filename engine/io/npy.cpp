#include "io/npy.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "io/atomic_file.h"

namespace evflow::io {

namespace fs = std::filesystem;
static_assert(std::endian::native == std::endian::little, "npy I/O assumes a little-endian host");

size_t dtype_size(DType d) {
  switch (d) {
    case DType::f4:
    case DType::i4:
    case DType::u4:
      return 4;
    case DType::f8:
    case DType::i8:
    case DType::u8:
      return 8;
    case DType::i2:
    case DType::u2:
      return 2;
    case DType::i1:
    case DType::u1:
    case DType::b1:
      return 1;
  }
  return 0;
}

std::string dtype_descr(DType d) {
  switch (d) {
    case DType::f4:
      return "<f4";
    case DType::f8:
      return "<f8";
    case DType::i1:
      return "|i1";
    case DType::i2:
      return "<i2";
    case DType::i4:
      return "<i4";
    case DType::i8:
      return "<i8";
    case DType::u1:
      return "|u1";
    case DType::u2:
      return "<u2";
    case DType::u4:
      return "<u4";
    case DType::u8:
      return "<u8";
    case DType::b1:
      return "|b1";
  }
  return "?";
}

size_t NpyArray::count() const {
  size_t n = 1;
  for (size_t s : shape) n *= s;
  return n;
}

namespace {

template <typename T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

template <typename Out>
std::vector<Out> convert(const NpyArray& a) {
  const size_t n = a.count();
  std::vector<Out> out(n);
  const uint8_t* b = a.bytes.data();
  for (size_t i = 0; i < n; ++i) {
    switch (a.dtype) {
      case DType::f4:
        out[i] = Out(load<float>(b + 4 * i));
        break;
      case DType::f8:
        out[i] = Out(load<double>(b + 8 * i));
        break;
      case DType::i1:
        out[i] = Out(load<int8_t>(b + i));
        break;
      case DType::i2:
        out[i] = Out(load<int16_t>(b + 2 * i));
        break;
      case DType::i4:
        out[i] = Out(load<int32_t>(b + 4 * i));
        break;
      case DType::i8:
        out[i] = Out(load<int64_t>(b + 8 * i));
        break;
      case DType::u1:
        out[i] = Out(load<uint8_t>(b + i));
        break;
      case DType::u2:
        out[i] = Out(load<uint16_t>(b + 2 * i));
        break;
      case DType::u4:
        out[i] = Out(load<uint32_t>(b + 4 * i));
        break;
      case DType::u8:
        out[i] = Out(load<uint64_t>(b + 8 * i));
        break;
      case DType::b1:
        out[i] = Out(b[i] ? 1 : 0);
        break;
    }
  }
  return out;
}

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

// Finds the value text after 'key': in the header dict.
std::string dict_value(const fs::path& path, const std::string& header, const std::string& key) {
  size_t k = header.find("'" + key + "'");
  if (k == std::string::npos) k = header.find("\"" + key + "\"");
  if (k == std::string::npos) fail(path, "npy header has no '" + key + "' entry: " + header);
  size_t colon = header.find(':', k + key.size() + 2);
  if (colon == std::string::npos) fail(path, "malformed npy header: " + header);
  size_t s = header.find_first_not_of(" \t", colon + 1);
  if (s == std::string::npos) fail(path, "malformed npy header: " + header);
  char open = header[s];
  size_t e;
  if (open == '\'' || open == '"') {
    e = header.find(open, s + 1);
    if (e == std::string::npos) fail(path, "malformed npy header: " + header);
    return header.substr(s + 1, e - s - 1);
  }
  if (open == '(' || open == '[') {
    e = header.find(open == '(' ? ')' : ']', s);
    if (e == std::string::npos) fail(path, "malformed npy header: " + header);
    return header.substr(s, e - s + 1);
  }
  e = header.find_first_of(",}", s);
  if (e == std::string::npos) fail(path, "malformed npy header: " + header);
  std::string v = header.substr(s, e - s);
  while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.pop_back();
  return v;
}

DType parse_descr(const fs::path& path, const std::string& d) {
  if (d.size() < 2) fail(path, "unsupported npy dtype '" + d + "'");
  char order = d[0];
  std::string code = d.substr(1);
  if (order == '>') fail(path, "big-endian npy dtype '" + d + "' is not supported (save it little-endian)");
  if (order != '<' && order != '|' && order != '=') fail(path, "unsupported npy dtype '" + d + "'");
  if (code == "f4") return DType::f4;
  if (code == "f8") return DType::f8;
  if (code == "i1") return DType::i1;
  if (code == "i2") return DType::i2;
  if (code == "i4") return DType::i4;
  if (code == "i8") return DType::i8;
  if (code == "u1") return DType::u1;
  if (code == "u2") return DType::u2;
  if (code == "u4") return DType::u4;
  if (code == "u8") return DType::u8;
  if (code == "b1" || code == "?") return DType::b1;
  fail(path, "unsupported npy dtype '" + d + "' (supported: f4 f8 i1 i2 i4 i8 u1 u2 u4 u8 b1, little-endian)");
}

std::vector<size_t> parse_shape(const fs::path& path, const std::string& s) {
  if (s.size() < 2 || s.front() != '(' || s.back() != ')') fail(path, "malformed npy shape '" + s + "'");
  std::vector<size_t> shape;
  size_t i = 1;
  while (i + 1 < s.size()) {
    while (i + 1 < s.size() && (s[i] == ' ' || s[i] == ',')) ++i;
    if (i + 1 >= s.size()) break;
    size_t j = i;
    while (j < s.size() && s[j] >= '0' && s[j] <= '9') ++j;
    if (j == i || j - i > 18) fail(path, "malformed npy shape '" + s + "'");
    shape.push_back(std::stoull(s.substr(i, j - i)));
    i = j;
    while (i + 1 < s.size() && s[i] == ' ') ++i;
    if (i + 1 < s.size() && s[i] != ',') fail(path, "malformed npy shape '" + s + "'");
  }
  return shape;
}

}  // namespace

std::vector<double> NpyArray::to_double() const { return convert<double>(*this); }
std::vector<float> NpyArray::to_float() const { return convert<float>(*this); }

template <typename T>
std::vector<T> NpyArray::as() const {
  if (dtype != dtype_of<T>())
    throw std::runtime_error(source + ": npy dtype is " + dtype_descr(dtype) + ", expected " +
                             dtype_descr(dtype_of<T>()));
  std::vector<T> out(count());
  if (!out.empty()) std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

NpyArray read_npy(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path, "cannot open file (missing or unreadable)");
  f.seekg(0, std::ios::end);
  const auto file_size = static_cast<uint64_t>(f.tellg());
  f.seekg(0);
  unsigned char pre[10];
  if (file_size < 10 || !f.read(reinterpret_cast<char*>(pre), 10)) fail(path, "truncated npy file (no header)");
  if (std::memcmp(pre, "\x93NUMPY", 6) != 0) fail(path, "not an npy file (bad magic bytes)");
  const int major = pre[6];
  uint64_t header_len, offset;
  if (major == 1) {
    header_len = pre[8] | (uint64_t(pre[9]) << 8);
    offset = 10;
  } else if (major == 2 || major == 3) {
    unsigned char b[2];
    if (!f.read(reinterpret_cast<char*>(b), 2)) fail(path, "truncated npy file (no header)");
    header_len = pre[8] | (uint64_t(pre[9]) << 8) | (uint64_t(b[0]) << 16) | (uint64_t(b[1]) << 24);
    offset = 12;
  } else {
    fail(path, "unsupported npy format version " + std::to_string(major));
  }
  if (offset + header_len > file_size) fail(path, "truncated npy file (header runs past the end)");
  std::string header(header_len, '\0');
  f.read(header.data(), static_cast<std::streamsize>(header_len));
  if (!f) fail(path, "truncated npy file (header)");
  if (header.find('{') == std::string::npos || header.find('}') == std::string::npos)
    fail(path, "malformed npy header: " + header);

  NpyArray a;
  a.source = path.string();
  std::string descr_raw = dict_value(path, header, "descr");
  if (!descr_raw.empty() && (descr_raw[0] == '[' || descr_raw[0] == '('))
    fail(path, "structured npy dtypes are not supported");
  a.dtype = parse_descr(path, descr_raw);
  std::string fo = dict_value(path, header, "fortran_order");
  if (fo == "True") fail(path, "Fortran-order npy arrays are not supported (save with C order)");
  if (fo != "False") fail(path, "malformed npy header (fortran_order = '" + fo + "')");
  a.shape = parse_shape(path, dict_value(path, header, "shape"));

  const uint64_t data_bytes = file_size - offset - header_len;
  long double need_ld = dtype_size(a.dtype);
  for (size_t s : a.shape) need_ld *= s;
  if (need_ld != static_cast<long double>(data_bytes)) {
    std::string shape_s = "(";
    for (size_t i = 0; i < a.shape.size(); ++i) shape_s += (i ? ", " : "") + std::to_string(a.shape[i]);
    shape_s += ")";
    // A shape past 2^64 bytes cannot be converted to an integer (undefined behaviour): say so.
    const std::string need_s = need_ld < 0x1p64L ? std::to_string(uint64_t(need_ld)) : "more than 18446744073709551615";
    fail(path, std::string(need_ld > data_bytes ? "truncated npy file" : "npy header/shape mismatch") + ": shape " +
                   shape_s + " of " + dtype_descr(a.dtype) + " needs " + need_s + " bytes of data, the file has " +
                   std::to_string(data_bytes));
  }
  a.bytes.resize(data_bytes);
  if (data_bytes && !f.read(reinterpret_cast<char*>(a.bytes.data()), static_cast<std::streamsize>(data_bytes)))
    fail(path, "read error in npy data");
  return a;
}

std::vector<double> read_npy_double(const fs::path& path, std::vector<size_t>* shape) {
  NpyArray a = read_npy(path);
  if (shape) *shape = a.shape;
  return a.to_double();
}

void write_npy(const fs::path& path, DType dtype, const std::vector<size_t>& shape, const void* data) {
  std::string shape_s = "(";
  size_t n = 1;
  for (size_t i = 0; i < shape.size(); ++i) {
    shape_s += (i ? ", " : "") + std::to_string(shape[i]);
    n *= shape[i];
  }
  shape_s += shape.size() == 1 ? ",)" : ")";
  std::string header = "{'descr': '" + dtype_descr(dtype) + "', 'fortran_order': False, 'shape': " + shape_s + ", }";
  // Pad with spaces so that magic + length + header + '\n' is a multiple of 64 bytes.
  int version = 1;
  size_t pre = 10;
  if (header.size() + 1 + pre > 65535 + 10) {
    version = 2;
    pre = 12;
  }
  size_t total = pre + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  write_file_atomic(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) fail(path, "cannot create file");
    f.write("\x93NUMPY", 6);
    const unsigned char ver[2] = {static_cast<unsigned char>(version), 0};
    f.write(reinterpret_cast<const char*>(ver), 2);
    const uint64_t hl = header.size();
    if (version == 1) {
      const unsigned char l[2] = {static_cast<unsigned char>(hl & 0xff), static_cast<unsigned char>(hl >> 8)};
      f.write(reinterpret_cast<const char*>(l), 2);
    } else {
      const unsigned char l[4] = {static_cast<unsigned char>(hl & 0xff), static_cast<unsigned char>((hl >> 8) & 0xff),
                                  static_cast<unsigned char>((hl >> 16) & 0xff), static_cast<unsigned char>(hl >> 24)};
      f.write(reinterpret_cast<const char*>(l), 4);
    }
    f.write(header.data(), static_cast<std::streamsize>(header.size()));
    if (n) f.write(static_cast<const char*>(data), static_cast<std::streamsize>(n * dtype_size(dtype)));
    close_or_throw(f, path);
  });
}

template <typename T>
void write_npy(const fs::path& path, const std::vector<size_t>& shape, const std::vector<T>& data) {
  size_t n = 1;
  for (size_t s : shape) n *= s;
  if (n != data.size())
    throw std::invalid_argument(path.string() + ": write_npy: shape has " + std::to_string(n) + " elements, data " +
                                std::to_string(data.size()));
  if constexpr (std::is_same_v<T, bool>) {
    std::vector<uint8_t> b(data.begin(), data.end());
    write_npy(path, DType::b1, shape, b.data());
  } else {
    write_npy(path, dtype_of<T>(), shape, data.data());
  }
}

#define EVF_NPY_INSTANTIATE(T)                     \
  template std::vector<T> NpyArray::as<T>() const; \
  template void write_npy<T>(const fs::path&, const std::vector<size_t>&, const std::vector<T>&);
EVF_NPY_INSTANTIATE(float)
EVF_NPY_INSTANTIATE(double)
EVF_NPY_INSTANTIATE(int8_t)
EVF_NPY_INSTANTIATE(int16_t)
EVF_NPY_INSTANTIATE(int32_t)
EVF_NPY_INSTANTIATE(int64_t)
EVF_NPY_INSTANTIATE(uint8_t)
EVF_NPY_INSTANTIATE(uint16_t)
EVF_NPY_INSTANTIATE(uint32_t)
EVF_NPY_INSTANTIATE(uint64_t)
#undef EVF_NPY_INSTANTIATE

// std::vector<bool> is bit-packed: specialise as<bool>.
template <>
std::vector<bool> NpyArray::as<bool>() const {
  if (dtype != DType::b1) throw std::runtime_error(source + ": npy dtype is " + dtype_descr(dtype) + ", expected |b1");
  std::vector<bool> out(count());
  for (size_t i = 0; i < out.size(); ++i) out[i] = bytes[i] != 0;
  return out;
}
template void write_npy<bool>(const fs::path&, const std::vector<size_t>&, const std::vector<bool>&);

}  // namespace evflow::io
