#include "io/dataset_formats.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

namespace evflow::io::detail {

namespace fs = std::filesystem;
using nlohmann::json;

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Numeric stems compare as numbers ("2" < "10"), everything else by name.
bool name_less(const fs::path& a, const fs::path& b) {
  const std::string sa = a.stem().string(), sb = b.stem().string();
  if (all_digits(sa) && all_digits(sb)) {
    const std::string ta = sa.substr(std::min(sa.find_first_not_of('0'), sa.size() - 1));
    const std::string tb = sb.substr(std::min(sb.find_first_not_of('0'), sb.size() - 1));
    if (ta.size() != tb.size()) return ta.size() < tb.size();
    if (ta != tb) return ta < tb;
  }
  return a.filename().string() < b.filename().string();
}

}  // namespace

bool is_image_file(const fs::path& p) {
  const std::string e = lower(p.extension().string());
  return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".exr" || e == ".tif" || e == ".tiff";
}

std::vector<fs::path> list_files(const fs::path& dir, bool (*keep)(const fs::path&)) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) fail(dir, "folder is missing");
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().filename().string()[0] != '.' && keep(e.path())) out.push_back(e.path());
  if (ec) fail(dir, "cannot list folder: " + ec.message());
  std::sort(out.begin(), out.end(), name_less);
  return out;
}

void require_file(const fs::path& p, const std::string& what) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) fail(p, what + " is missing");
}

// Image read + size check.
Image load_view_image(const fs::path& p, uint32_t w, uint32_t h) {
  require_file(p, "view image");
  Image im = read_image(p);
  if (w && (im.width != w || im.height != h))
    fail(p, "wrong image size " + std::to_string(im.width) + "x" + std::to_string(im.height) + ", expected " +
                std::to_string(w) + "x" + std::to_string(h));
  return im;
}

// Fits the LLFF camera's intrinsics to the actual image size (LLFF files may store the
// full-resolution h, w, f of images that were downsampled).
void fit_camera_to_image(Camera& cam, uint32_t w, uint32_t h, const fs::path& poses, size_t row,
                         const fs::path& image) {
  if (cam.width == w && cam.height == h) return;
  const double sx = double(w) / cam.width, sy = double(h) / cam.height;
  if (std::fabs(cam.height * sx - h) > 1.0 || std::fabs(cam.width * sy - w) > 1.0)  // rounded downsampling
    fail(image, "wrong image size " + std::to_string(w) + "x" + std::to_string(h) + ": row " + std::to_string(row) +
                    " of " + poses.string() + " is for " + std::to_string(cam.width) + "x" +
                    std::to_string(cam.height));
  cam.fx *= sx;
  cam.fy *= sy;
  cam.width = w;
  cam.height = h;
  cam.cx = 0.5 * w;
  cam.cy = 0.5 * h;
}

void set_bounds(Dataset& ds, const PosesBounds& pb) {
  if (pb.near.empty()) return;
  ds.near = *std::min_element(pb.near.begin(), pb.near.end());
  ds.far = *std::max_element(pb.far.begin(), pb.far.end());
}

json read_json_file(const fs::path& p) {
  std::ifstream f(p);
  if (!f) fail(p, "cannot open manifest");
  try {
    return json::parse(f);
  } catch (const std::exception& e) { fail(p, std::string("malformed JSON: ") + e.what()); }
}

const json& get(const json& j, const char* key, const fs::path& file, const std::string& where) {
  if (!j.is_object() || !j.contains(key)) fail(file, where + ": missing \"" + key + "\"");
  return j.at(key);
}

}  // namespace evflow::io::detail
