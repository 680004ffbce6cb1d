// Weights as safetensors (engine/nn/safetensors.h): a bit-exact round trip through a file, the
// layout Python readers expect, and clear refusals of truncated or damaged files.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>

#include "nn/safetensors.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

nn::SafetensorsFile sample() {
  nn::SafetensorsFile f;
  const float inf = std::numeric_limits<float>::infinity(), denormal = std::numeric_limits<float>::denorm_min();
  f.tensors.push_back({"ldi.0.weight", {2, 1, 3, 3}, {}});
  for (int i = 0; i < 18; ++i) f.tensors[0].values.push_back(float(i) * 0.37f - 3.1f);
  f.tensors[0].values[3] = -0.0f, f.tensors[0].values[4] = inf, f.tensors[0].values[5] = denormal;
  f.tensors.push_back({"ldi.0.bias", {2}, {1.5f, -2.25f}});
  f.tensors.push_back({"empty", {0, 4}, {}});
  f.metadata["format"] = "evflow";
  f.metadata["widths"] = "1,2";
  return f;
}

std::string header_of(const std::string& bytes) {
  uint64_t n = 0;
  for (int i = 7; i >= 0; --i) n = (n << 8) | uint8_t(bytes[size_t(i)]);
  return bytes.substr(8, n);
}

// Replaces the header with `json` (padded to keep the data where it was when it fits).
std::string with_header(const std::string& bytes, const std::string& json) {
  const std::string old = header_of(bytes);
  std::string h = json;
  if (h.size() < old.size()) h.append(old.size() - h.size(), ' ');
  std::string out(8, '\0');
  for (int i = 0; i < 8; ++i) out[size_t(i)] = char((uint64_t(h.size()) >> (8 * i)) & 0xFF);
  return out + h + bytes.substr(8 + old.size());
}

}  // namespace

TEST_CASE("safetensors: a file round trip keeps every bit, the names, shapes and metadata", "[safetensors]") {
  const fs::path path = fs::temp_directory_path() / "evflow_test_weights.safetensors";
  const nn::SafetensorsFile f = sample();
  nn::save_safetensors(path, f);
  const nn::SafetensorsFile g = nn::load_safetensors(path);
  fs::remove(path);
  REQUIRE(g.tensors.size() == f.tensors.size());
  for (size_t i = 0; i < f.tensors.size(); ++i) {
    CHECK(g.tensors[i].name == f.tensors[i].name);
    CHECK(g.tensors[i].shape == f.tensors[i].shape);
    REQUIRE(g.tensors[i].values.size() == f.tensors[i].values.size());
    CHECK(std::memcmp(g.tensors[i].values.data(), f.tensors[i].values.data(), f.tensors[i].values.size() * 4) == 0);
  }
  CHECK(g.metadata == f.metadata);
  REQUIRE(g.find("ldi.0.bias"));
  CHECK(g.find("nothing") == nullptr);
}

TEST_CASE("safetensors: the layout: length, JSON header padded to 8, offsets, little-endian data", "[safetensors]") {
  const std::string bytes = nn::encode_safetensors(sample());
  const std::string h = header_of(bytes);
  CHECK((8 + h.size()) % 8 == 0);
  const auto j = nlohmann::json::parse(h);
  CHECK(j["ldi.0.weight"]["dtype"] == "F32");
  CHECK(j["ldi.0.weight"]["shape"] == nlohmann::json::array({2, 1, 3, 3}));
  CHECK(j["ldi.0.weight"]["data_offsets"] == nlohmann::json::array({0, 72}));
  CHECK(j["ldi.0.bias"]["data_offsets"] == nlohmann::json::array({72, 80}));
  CHECK(j["__metadata__"]["format"] == "evflow");
  CHECK(bytes.size() == 8 + h.size() + 80);
  // 1.5f = 0x3FC00000, stored low byte first.
  const std::string one_and_half = bytes.substr(8 + h.size() + 72, 4);
  CHECK(one_and_half == std::string("\x00\x00\xC0\x3F", 4));
}

TEST_CASE("safetensors: truncated and damaged files are refused with the file and the fault named", "[safetensors]") {
  const std::string good = nn::encode_safetensors(sample());
  const std::string h = header_of(good);
  auto refuses = [](const std::string& bytes, const std::string& what) {
    INFO("expecting: " << what);
    REQUIRE_THROWS_WITH(nn::decode_safetensors(bytes, "w.safetensors"),
                        Catch::StartsWith("w.safetensors: safetensors: ") && Catch::Contains(what));
  };
  refuses(good.substr(0, 5), "shorter than the 8-byte header length");
  refuses(good.substr(0, 8 + h.size() / 2), "truncated");
  refuses(good.substr(0, 8 + h.size() - 4), "truncated");
  refuses(good.substr(0, good.size() - 4), "truncated");
  refuses(good + "xxxx", "cover 80 bytes of data, the file holds 84");
  refuses(with_header(good, "{\"a\": [1, 2"), "not valid JSON");
  refuses(with_header(good, "[1, 2, 3]"), "not a JSON object");
  std::string huge = good;
  huge[7] = char(0x7F);
  refuses(huge, "exceeds 100 MB");
  auto j = nlohmann::json::parse(h);
  auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    auto k = j;
    edit(k);
    return with_header(good, k.dump());
  };
  refuses(edited([](auto& k) { k["ldi.0.bias"]["dtype"] = "F16"; }), "dtype \"F16\" (only F32 is read)");
  refuses(edited([](auto& k) { k["ldi.0.bias"]["shape"] = {3}; }), "8 bytes of data for shape [3]");
  refuses(edited([](auto& k) { k["ldi.0.bias"]["shape"] = {-2}; }), "not a non-negative integer");
  refuses(edited([](auto& k) { k["ldi.0.bias"]["data_offsets"] = {68, 76}; }), "overlap or leave a gap");
  refuses(edited([](auto& k) { k["ldi.0.bias"]["data_offsets"] = {72, 800}; }), "ends at byte 800");
  refuses(edited([](auto& k) { k["ldi.0.bias"].erase("shape"); }), "has no shape");
  refuses(edited([](auto& k) { k["__metadata__"]["n"] = 3; }), "is not a string");
  refuses(edited([](auto& k) {
            k["ldi.0.weight"]["shape"] = {uint64_t(1) << 40, uint64_t(1) << 40, 1};
          }),
          "bytes of data for shape");
}

TEST_CASE("safetensors: a missing file and a failed write name the file", "[safetensors]") {
  REQUIRE_THROWS_WITH(nn::load_safetensors("/nonexistent/w.safetensors"),
                      Catch::Contains("/nonexistent/w.safetensors"));
  nn::SafetensorsFile twice;
  twice.tensors.push_back({"a", {1}, {1.0f}});
  twice.tensors.push_back({"a", {1}, {2.0f}});
  REQUIRE_THROWS_WITH(nn::encode_safetensors(twice), Catch::Contains("repeated"));
  nn::SafetensorsFile wrong;
  wrong.tensors.push_back({"a", {2, 2}, {1.0f}});
  REQUIRE_THROWS_WITH(nn::encode_safetensors(wrong), Catch::Contains("values for its shape"));
}
