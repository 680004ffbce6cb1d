// NumPy .npy files (format versions 1, 2 and 3): little-endian numeric dtypes, C order.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace evflow::io {

enum class DType { f4, f8, i1, i2, i4, i8, u1, u2, u4, u8, b1 };

size_t dtype_size(DType);
std::string dtype_descr(DType);  // NumPy descr, e.g. "<f8", "|u1", "|b1"

// Compile-time mapping C++ type -> DType (bool maps to b1).
template <typename T>
constexpr DType dtype_of();
template <>
constexpr DType dtype_of<float>() {
  return DType::f4;
}
template <>
constexpr DType dtype_of<double>() {
  return DType::f8;
}
template <>
constexpr DType dtype_of<int8_t>() {
  return DType::i1;
}
template <>
constexpr DType dtype_of<int16_t>() {
  return DType::i2;
}
template <>
constexpr DType dtype_of<int32_t>() {
  return DType::i4;
}
template <>
constexpr DType dtype_of<int64_t>() {
  return DType::i8;
}
template <>
constexpr DType dtype_of<uint8_t>() {
  return DType::u1;
}
template <>
constexpr DType dtype_of<uint16_t>() {
  return DType::u2;
}
template <>
constexpr DType dtype_of<uint32_t>() {
  return DType::u4;
}
template <>
constexpr DType dtype_of<uint64_t>() {
  return DType::u8;
}
template <>
constexpr DType dtype_of<bool>() {
  return DType::b1;
}

struct NpyArray {
  std::string source;  // file it was read from (for error messages)
  DType dtype = DType::f8;
  std::vector<size_t> shape;   // empty = scalar (one element)
  std::vector<uint8_t> bytes;  // raw little-endian data, C order

  size_t count() const;
  // Every element converted to double / float (bool -> 0/1).
  std::vector<double> to_double() const;
  std::vector<float> to_float() const;
  // The data as T; throws std::runtime_error naming `source` unless dtype == dtype_of<T>().
  template <typename T>
  std::vector<T> as() const;
};

template <>
std::vector<bool> NpyArray::as<bool>() const;

// Throws std::runtime_error naming the file on: unreadable file, bad magic, unsupported version,
// malformed header, big-endian / structured / unsupported dtype, Fortran order, and data whose
// size differs from what the shape needs (truncated file or trailing bytes).
NpyArray read_npy(const std::filesystem::path& path);
// Reads and converts; `shape` (optional) receives the array's shape.
std::vector<double> read_npy_double(const std::filesystem::path& path, std::vector<size_t>* shape = nullptr);

// Writes atomically (io/atomic_file.h); `data` holds product(shape) elements of `dtype`.
void write_npy(const std::filesystem::path& path, DType dtype, const std::vector<size_t>& shape, const void* data);
template <typename T>
void write_npy(const std::filesystem::path& path, const std::vector<size_t>& shape, const std::vector<T>& data);

}  // namespace evflow::io
