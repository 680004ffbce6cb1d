// What `evflow train --resume` repairs in a run folder whose run was killed: curve.csv rows past
// the checkpoint it continues from (they will be trained again) and a half-written last row.
#pragma once
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "io/atomic_file.h"

namespace evflow::app {

// Keeps curve.csv's header and its complete rows up to `step` (the first field), in order, and
// drops the rest. A missing file is left missing.
inline void trim_curve(const std::filesystem::path& path, uint32_t step) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  size_t keep = 0, pos = 0;
  for (bool header = true; pos < text.size(); header = false) {
    const size_t end = text.find('\n', pos);
    if (end == std::string::npos) break;  // a half-written last row
    if (!header) {
      char* stop = nullptr;
      const unsigned long s = std::strtoul(text.c_str() + pos, &stop, 10);
      if (stop == text.c_str() + pos || *stop != ',' || s > step) break;
    }
    keep = pos = end + 1;
  }
  if (keep == text.size()) return;
  io::write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(text.data(), std::streamsize(keep));
    io::close_or_throw(f, path);
  });
}

}  // namespace evflow::app
