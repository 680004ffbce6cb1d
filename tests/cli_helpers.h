// Helpers of the tests that run the `evflow` program (viewer tests under Xvfb).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "io/image.h"

namespace evflow::test {

// The folders fresh_dir made in this process, removed when the test program exits normally
// (a crashed run leaves them for a look).
inline std::vector<std::filesystem::path>& fresh_dirs() {
  static struct Registry {
    std::vector<std::filesystem::path> dirs;
    ~Registry() {
      for (const auto& d : dirs) {
        std::error_code ec;
        std::filesystem::remove_all(d, ec);
      }
    }
  } registry;
  return registry.dirs;
}

// An empty folder <tmp>/<name>_<pid> (removed first if it exists; removed again at exit).
inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  fresh_dirs().push_back(d);
  return d;
}

// build/evflow, next to build/tests/evflow_tests.
inline std::filesystem::path evflow_binary() {
  return std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path() / "evflow";
}

inline bool on_path(const std::string& prog) {
  return std::system(("command -v " + prog + " >/dev/null 2>&1").c_str()) == 0;
}

// Single-quoted for sh.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// Runs the evflow binary with `args` in `dir` (10 minutes at most); returns its exit status,
// its output (stdout and stderr) in `out`.
inline int run_evflow(const std::filesystem::path& dir, const std::string& args, std::string& out) {
  const std::filesystem::path log = dir / "run.log";
  const std::string cmd = "cd " + quote(dir.string()) + " && timeout 600 " + quote(evflow_binary().string()) + " " +
                          args + " > " + quote(log.string()) + " 2>&1";
  const int status = std::system(cmd.c_str());
  out = slurp(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The text of a docs/ file between "<!-- begin: COMMAND -->" and "<!-- end: COMMAND -->" (the
// output of COMMAND kept in the docs); "(markers missing)" when the file lacks them.
inline std::string generated_section(const std::string& doc_file, const std::string& command) {
  const std::string doc = slurp(std::filesystem::path(EVF_SOURCE_DIR) / "docs" / doc_file);
  const std::string begin = "<!-- begin: " + command + " -->\n", end = "<!-- end: " + command + " -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  if (b == std::string::npos || e == std::string::npos || e < b) return "(markers missing)";
  return doc.substr(b + begin.size(), e - b - begin.size());
}

// A linear value as the 8-bit sRGB byte a screenshot holds.
inline uint8_t encode8(float linear) {
  float v = std::isnan(linear) ? 0.f : std::clamp(linear, 0.f, 1.f);
  return static_cast<uint8_t>(std::lround(io::linear_to_srgb(v) * 255.f));
}
// An sRGB-valued float (a render: splat colours are sRGB) as the 8-bit value a PNG or the canvas holds.
inline uint8_t quantise8(float srgb) {
  float v = std::isnan(srgb) ? 0.f : std::clamp(srgb, 0.f, 1.f);
  return static_cast<uint8_t>(std::lround(v * 255.f));
}

}  // namespace evflow::test
