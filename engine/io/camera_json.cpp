#include "io/camera_json.h"

#include <cmath>
#include <fstream>
#include <stdexcept>

namespace evflow::io {

namespace {

double number(const nlohmann::json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j[key].is_number())
    throw std::runtime_error(where + ": '" + key + "' missing or not a number");
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw std::runtime_error(where + ": '" + key + "' is not finite");
  return v;
}

// The 12 numbers of [R | t], row-major, from 4 rows, 3 rows or 16 numbers.
std::vector<double> w2c_values(const nlohmann::json& j, const std::string& where) {
  if (!j.contains("w2c") || !j["w2c"].is_array())
    throw std::runtime_error(where + ": 'w2c' (world-to-camera matrix) missing");
  std::vector<double> flat;
  for (auto& row : j["w2c"]) {
    if (row.is_array())
      for (auto& x : row) flat.push_back(x.is_number() ? x.get<double>() : NAN);
    else
      flat.push_back(row.is_number() ? row.get<double>() : NAN);
  }
  if (flat.size() != 12 && flat.size() != 16)
    throw std::runtime_error(where + ": 'w2c' has " + std::to_string(flat.size()) + " numbers (3x4 or 4x4 expected)");
  for (double x : flat)
    if (!std::isfinite(x)) throw std::runtime_error(where + ": 'w2c' holds a value that is not a finite number");
  flat.resize(12);
  return flat;
}

void check_rotation(const Camera& c, const std::string& where) {
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += c.R[a * 3 + k] * c.R[b * 3 + k];
      if (std::abs(d - (a == b ? 1.0 : 0.0)) > 1e-4)
        throw std::runtime_error(where + ": 'w2c' rotation is not orthonormal");
    }
  const double det = c.R[0] * (c.R[4] * c.R[8] - c.R[5] * c.R[7]) - c.R[1] * (c.R[3] * c.R[8] - c.R[5] * c.R[6]) +
                     c.R[2] * (c.R[3] * c.R[7] - c.R[4] * c.R[6]);
  if (det < 0) throw std::runtime_error(where + ": 'w2c' rotation is a reflection (determinant -1)");
}

}  // namespace

Camera camera_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw std::runtime_error(where + ": not a JSON object");
  Camera c;
  const double w = number(j, "width", where), h = number(j, "height", where);
  if (w < 1 || h < 1 || w > 16384 || h > 16384 || w != std::floor(w) || h != std::floor(h))
    throw std::runtime_error(where + ": width and height must be whole numbers in 1..16384");
  c.width = uint32_t(w), c.height = uint32_t(h);
  c.fx = number(j, "fx", where), c.fy = number(j, "fy", where);
  c.cx = number(j, "cx", where), c.cy = number(j, "cy", where);
  if (!(c.fx > 0 && c.fy > 0)) throw std::runtime_error(where + ": fx and fy must be positive");
  const auto m = w2c_values(j, where);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c.R[r * 3 + k] = m[r * 4 + k];
    c.t[r] = m[r * 4 + 3];
  }
  check_rotation(c, where);
  return c;
}

nlohmann::json camera_to_json(const Camera& c) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({c.R[r * 3], c.R[r * 3 + 1], c.R[r * 3 + 2], c.t[r]});
  rows.push_back({0, 0, 0, 1});
  return {{"width", c.width}, {"height", c.height}, {"fx", c.fx}, {"fy", c.fy},
          {"cx", c.cx},       {"cy", c.cy},         {"w2c", rows}};
}

std::vector<Camera> read_cameras_json(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path.string() + ": cannot open the camera file");
  nlohmann::json j;
  try {
    f >> j;
  } catch (const std::exception& e) { throw std::runtime_error(path.string() + ": not valid JSON (" + e.what() + ")"); }
  if (j.is_object() && j.contains("cameras")) j = j["cameras"];
  if (j.is_object()) j = nlohmann::json::array({j});
  if (!j.is_array() || j.empty()) throw std::runtime_error(path.string() + ": holds no camera");
  std::vector<Camera> out;
  for (size_t i = 0; i < j.size(); ++i)
    out.push_back(camera_from_json(j[i], path.string() + ": camera " + std::to_string(i)));
  return out;
}

}  // namespace evflow::io
