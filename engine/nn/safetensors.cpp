#include "nn/safetensors.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.h"
#include "nn/little_endian.h"

namespace evflow::nn {

namespace {

uint64_t product(const std::vector<uint64_t>& shape) {
  uint64_t p = 1;
  for (uint64_t d : shape) p *= d;
  return p;
}

}  // namespace

const NamedTensor* SafetensorsFile::find(const std::string& name) const {
  for (auto& t : tensors)
    if (t.name == name) return &t;
  return nullptr;
}

std::string encode_safetensors(const SafetensorsFile& file) {
  nlohmann::ordered_json header = nlohmann::ordered_json::object();
  if (!file.metadata.empty()) header["__metadata__"] = file.metadata;
  uint64_t offset = 0;
  std::set<std::string> names;
  for (auto& t : file.tensors) {
    if (t.name.empty() || t.name == "__metadata__" || !names.insert(t.name).second)
      throw std::invalid_argument("safetensors: tensor name '" + t.name + "' is empty, reserved or repeated");
    if (product(t.shape) != t.values.size())
      throw std::invalid_argument("safetensors: tensor " + t.name + " has " + std::to_string(t.values.size()) +
                                  " values for its shape");
    const uint64_t end = offset + t.values.size() * 4;
    header[t.name] = {{"dtype", "F32"}, {"shape", t.shape}, {"data_offsets", {offset, end}}};
    offset = end;
  }
  std::string json = header.dump();
  json.append((8 - json.size() % 8) % 8, ' ');
  std::string out(8 + json.size() + offset, '\0');
  const uint64_t n = json.size();
  for (int i = 0; i < 8; ++i) out[i] = char((n >> (8 * i)) & 0xFF);
  std::memcpy(&out[8], json.data(), json.size());
  char* data = &out[8 + json.size()];
  for (auto& t : file.tensors) {
    floats_to_le(t.values.data(), t.values.size(), data);
    data += t.values.size() * 4;
  }
  return out;
}

void save_safetensors(const std::filesystem::path& path, const SafetensorsFile& file) {
  const std::string bytes = encode_safetensors(file);
  io::write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    io::close_or_throw(f, path);
  });
}

SafetensorsFile load_safetensors(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path.string() + ": cannot open the safetensors file");
  std::ostringstream s;
  s << f.rdbuf();
  if (f.bad()) throw std::runtime_error(path.string() + ": read error");
  return decode_safetensors(s.str(), path.string());
}

}  // namespace evflow::nn
