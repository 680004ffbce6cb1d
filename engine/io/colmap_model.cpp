#include "io/colmap_model.h"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace evflow::io {

namespace fs = std::filesystem;

namespace {

// The file's lines that are not comments, with their line numbers. Blank lines are kept:
// images.txt writes an empty second line for an image without 2D points.
struct Lines {
  std::vector<std::string> text;
  std::vector<size_t> number;
};

Lines read_lines(const fs::path& p) {
  std::ifstream f(p);
  if (!f) throw std::runtime_error(p.string() + ": cannot open the COLMAP model file");
  Lines l;
  std::string s;
  for (size_t n = 1; std::getline(f, s); ++n) {
    if (!s.empty() && s.back() == '\r') s.pop_back();
    if (!s.empty() && s[0] == '#') continue;
    l.text.push_back(s);
    l.number.push_back(n);
  }
  return l;
}

[[noreturn]] void bad_line(const fs::path& p, size_t line, const std::string& what) {
  throw std::runtime_error(p.string() + ":" + std::to_string(line) + ": " + what);
}

struct Intrinsics {
  uint32_t width, height;
  double fx, fy, cx, cy;
};

std::map<uint32_t, Intrinsics> read_cameras(const fs::path& p) {
  const Lines l = read_lines(p);
  std::map<uint32_t, Intrinsics> cams;
  for (size_t i = 0; i < l.text.size(); ++i) {
    if (l.text[i].find_first_not_of(" \t") == std::string::npos) continue;
    std::istringstream s(l.text[i]);
    uint32_t id;
    std::string model;
    Intrinsics k{};
    if (!(s >> id >> model >> k.width >> k.height)) bad_line(p, l.number[i], "expected CAMERA_ID MODEL WIDTH HEIGHT");
    if (model == "PINHOLE") {
      if (!(s >> k.fx >> k.fy >> k.cx >> k.cy)) bad_line(p, l.number[i], "PINHOLE needs fx fy cx cy");
    } else if (model == "SIMPLE_PINHOLE") {
      if (!(s >> k.fx >> k.cx >> k.cy)) bad_line(p, l.number[i], "SIMPLE_PINHOLE needs f cx cy");
      k.fy = k.fx;
    } else {
      bad_line(p, l.number[i], "camera model " + model + " is not supported (PINHOLE or SIMPLE_PINHOLE)");
    }
    cams[id] = k;
  }
  return cams;
}

// Hamilton quaternion (w, x, y, z), normalised, to a row-major rotation.
std::array<double, 9> quaternion_rotation(double w, double x, double y, double z) {
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  w /= n, x /= n, y /= n, z /= n;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

std::vector<ColmapImage> read_images(const fs::path& p, const std::map<uint32_t, Intrinsics>& cams) {
  const Lines l = read_lines(p);
  std::vector<ColmapImage> images;
  for (size_t i = 0; i < l.text.size(); i += 2) {
    if (l.text[i].find_first_not_of(" \t") == std::string::npos) {
      --i;  // a stray blank line between images
      continue;
    }
    std::istringstream s(l.text[i]);
    ColmapImage im;
    double q[4], t[3];
    if (!(s >> im.id >> q[0] >> q[1] >> q[2] >> q[3] >> t[0] >> t[1] >> t[2] >> im.camera_id))
      bad_line(p, l.number[i], "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    std::getline(s >> std::ws, im.name);
    if (im.name.empty()) bad_line(p, l.number[i], "the image has no name");
    auto k = cams.find(im.camera_id);
    if (k == cams.end()) bad_line(p, l.number[i], "camera " + std::to_string(im.camera_id) + " is not in cameras.txt");
    if (!(std::fabs(q[0]) + std::fabs(q[1]) + std::fabs(q[2]) + std::fabs(q[3]) > 0))
      bad_line(p, l.number[i], "zero quaternion");
    im.camera.width = k->second.width;
    im.camera.height = k->second.height;
    im.camera.fx = k->second.fx;
    im.camera.fy = k->second.fy;
    im.camera.cx = k->second.cx;
    im.camera.cy = k->second.cy;
    im.camera.R = quaternion_rotation(q[0], q[1], q[2], q[3]);
    im.camera.t = {t[0], t[1], t[2]};
    images.push_back(std::move(im));
  }
  return images;
}

std::vector<ColmapPoint> read_points(const fs::path& p) {
  const Lines l = read_lines(p);
  std::vector<ColmapPoint> points;
  for (size_t i = 0; i < l.text.size(); ++i) {
    if (l.text[i].find_first_not_of(" \t") == std::string::npos) continue;
    std::istringstream s(l.text[i]);
    uint64_t id;
    int rgb[3];
    ColmapPoint pt;
    if (!(s >> id >> pt.xyz[0] >> pt.xyz[1] >> pt.xyz[2] >> rgb[0] >> rgb[1] >> rgb[2] >> pt.error))
      bad_line(p, l.number[i], "expected POINT3D_ID X Y Z R G B ERROR TRACK[]");
    for (int c = 0; c < 3; ++c) {
      if (rgb[c] < 0 || rgb[c] > 255) bad_line(p, l.number[i], "colour outside 0..255");
      pt.rgb[c] = uint8_t(rgb[c]);
    }
    uint32_t image, idx;
    while (s >> image >> idx) pt.image_ids.push_back(image);
    if (!s.eof()) bad_line(p, l.number[i], "malformed track (IMAGE_ID POINT2D_IDX pairs)");
    points.push_back(std::move(pt));
  }
  return points;
}

}  // namespace

ColmapModel read_colmap_text(const fs::path& dir) {
  ColmapModel m;
  m.images = read_images(dir / "images.txt", read_cameras(dir / "cameras.txt"));
  m.points = read_points(dir / "points3D.txt");
  return m;
}

}  // namespace evflow::io
