// Reading safetensors bytes (safetensors.h): every offset, shape and dtype is checked before a
// value is copied, so that a damaged file gives an error naming the file and what is wrong.
#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <tuple>

#include "nn/little_endian.h"
#include "nn/safetensors.h"

namespace evflow::nn {

namespace {

constexpr uint64_t kMaxHeaderBytes = 100u << 20;  // the format's own reader's limit: 100 MB

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw std::runtime_error(source + ": safetensors: " + what);
}

struct Entry {
  std::string name;
  std::vector<uint64_t> shape;
  uint64_t begin = 0, end = 0;
};

uint64_t read_u64_le(const std::string& b) {
  uint64_t n = 0;
  for (int i = 7; i >= 0; --i) n = (n << 8) | uint8_t(b[size_t(i)]);
  return n;
}

std::vector<uint64_t> unsigned_list(const nlohmann::json& j, const std::string& source, const std::string& what) {
  if (!j.is_array()) fail(source, what + " is not an array");
  std::vector<uint64_t> v;
  for (auto& e : j) {
    if (!e.is_number_unsigned()) fail(source, what + " holds " + e.dump() + ", not a non-negative integer");
    v.push_back(e.get<uint64_t>());
  }
  return v;
}

Entry parse_entry(const std::string& name, const nlohmann::json& j, uint64_t data_bytes, const std::string& source) {
  const std::string what = "tensor '" + name + "'";
  if (!j.is_object()) fail(source, what + " is not a JSON object");
  for (const char* key : {"dtype", "shape", "data_offsets"})
    if (!j.contains(key)) fail(source, what + " has no " + key);
  if (!j["dtype"].is_string() || j["dtype"] != "F32")
    fail(source, what + " has dtype " + j["dtype"].dump() + " (only F32 is read)");
  Entry e{name, unsigned_list(j["shape"], source, what + " shape"), 0, 0};
  const auto off = unsigned_list(j["data_offsets"], source, what + " data_offsets");
  if (off.size() != 2 || off[0] > off[1]) fail(source, what + " data_offsets is not [begin, end] with begin <= end");
  if (off[1] > data_bytes)
    fail(source, what + " ends at byte " + std::to_string(off[1]) + " of data, but the file holds " +
                     std::to_string(data_bytes) + " bytes of data (truncated?)");
  uint64_t count = 1;  // the shape's product, or above data_bytes when that overflows
  if (std::find(e.shape.begin(), e.shape.end(), 0) != e.shape.end()) count = 0;
  for (uint64_t d : e.shape) {
    if (count == 0 || count > data_bytes) break;
    count = count > data_bytes / d ? data_bytes + 1 : count * d;
  }
  if (count > data_bytes / 4 || count * 4 != off[1] - off[0])
    fail(source, what + " has " + std::to_string(off[1] - off[0]) + " bytes of data for shape " + j["shape"].dump());
  e.begin = off[0], e.end = off[1];
  return e;
}

// The tensors must cover the data exactly, one after another.
void check_layout(std::vector<Entry>& entries, uint64_t data_bytes, const std::string& source) {
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return std::tie(a.begin, a.end) < std::tie(b.begin, b.end); });
  uint64_t at = 0;
  for (auto& e : entries) {
    if (e.begin != at)
      fail(source, "tensor '" + e.name + "' starts at data byte " + std::to_string(e.begin) + ", expected " +
                       std::to_string(at) + " (tensors overlap or leave a gap)");
    at = e.end;
  }
  if (at != data_bytes)
    fail(source,
         "the tensors cover " + std::to_string(at) + " bytes of data, the file holds " + std::to_string(data_bytes));
}

std::map<std::string, std::string> parse_metadata(const nlohmann::json& j, const std::string& source) {
  if (!j.is_object()) fail(source, "__metadata__ is not a JSON object");
  std::map<std::string, std::string> m;
  for (auto& [k, v] : j.items()) {
    if (!v.is_string()) fail(source, "__metadata__ value of '" + k + "' is not a string");
    m[k] = v.get<std::string>();
  }
  return m;
}

}  // namespace

SafetensorsFile decode_safetensors(const std::string& bytes, const std::string& source) {
  if (bytes.size() < 8)
    fail(source, "file of " + std::to_string(bytes.size()) + " bytes is shorter than the 8-byte header length");
  const uint64_t n = read_u64_le(bytes);
  if (n > kMaxHeaderBytes) fail(source, "header length " + std::to_string(n) + " exceeds 100 MB");
  if (n > bytes.size() - 8)
    fail(source, "header length " + std::to_string(n) + " but only " + std::to_string(bytes.size() - 8) +
                     " bytes follow it (truncated?)");
  nlohmann::json header;
  try {
    header = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + std::ptrdiff_t(n));
  } catch (const nlohmann::json::exception& e) {
    fail(source, std::string("header is not valid JSON (") + e.what() + ")");
  }
  if (!header.is_object()) fail(source, "header is not a JSON object");
  const uint64_t data_bytes = bytes.size() - 8 - n;
  SafetensorsFile out;
  std::vector<Entry> entries;
  for (auto& [name, value] : header.items()) {
    if (name == "__metadata__")
      out.metadata = parse_metadata(value, source);
    else
      entries.push_back(parse_entry(name, value, data_bytes, source));
  }
  check_layout(entries, data_bytes, source);
  const char* data = bytes.data() + 8 + n;
  for (auto& e : entries) {
    NamedTensor t{e.name, e.shape, std::vector<float>((e.end - e.begin) / 4)};
    le_to_floats(data + e.begin, t.values.size(), t.values.data());
    out.tensors.push_back(std::move(t));
  }
  return out;
}

}  // namespace evflow::nn
