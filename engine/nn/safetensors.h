// Weights as safetensors files: an 8-byte little-endian header length N, N bytes of UTF-8 JSON,
// then the raw little-endian tensor data. The header maps each tensor's name to
// {"dtype": "F32", "shape": [...], "data_offsets": [begin, end]} (byte offsets into the data,
// which follows the header), plus an optional "__metadata__" object of strings. Readable from
// Python with numpy alone. Only F32 tensors are written and read.
#pragma once
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace evflow::nn {

struct NamedTensor {
  std::string name;
  std::vector<uint64_t> shape;
  std::vector<float> values;  // row-major, as many as the shape's product
};

struct SafetensorsFile {
  std::vector<NamedTensor> tensors;  // in data order
  std::map<std::string, std::string> metadata;
  const NamedTensor* find(const std::string& name) const;  // nullptr when absent
};

// The file's bytes: tensors laid out in the given order, the header padded with spaces to a
// multiple of 8 bytes. Throws std::invalid_argument for a duplicate or empty name, the reserved
// name "__metadata__" or values that do not match a shape.
std::string encode_safetensors(const SafetensorsFile& file);
// Writes through a temporary file renamed onto `path` (a failed write leaves the old file).
void save_safetensors(const std::filesystem::path& path, const SafetensorsFile& file);

// Parses a file's bytes; `source` names it in errors. Throws std::runtime_error
// "<source>: safetensors: <what is wrong>" for a truncated file, a header that is not a JSON
// object, a dtype other than F32, a shape that does not match its data, or offsets that lie
// outside the data, overlap or leave gaps.
SafetensorsFile decode_safetensors(const std::string& bytes, const std::string& source);
SafetensorsFile load_safetensors(const std::filesystem::path& path);

}  // namespace evflow::nn
