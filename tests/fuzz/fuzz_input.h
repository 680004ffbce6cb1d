// What the libFuzzer harnesses share: the input as a file (the readers take paths) and the rule
// every reader must keep: bad input ends in std::runtime_error or std::invalid_argument whose
// message names the file. Anything else (another exception, a crash, a sanitizer report, an
// allocation past libFuzzer's limit) is a finding.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace evflow::fuzz {

// A folder of this process's own, made once, under $EVF_FUZZ_DIR (scripts/fuzz.sh makes one in
// memory and removes it afterwards) or else /dev/shm.
inline const std::filesystem::path& work_dir() {
  static const std::filesystem::path dir = [] {
    const char* root = std::getenv("EVF_FUZZ_DIR");
    const std::filesystem::path d =
        std::filesystem::path(root && *root ? root : "/dev/shm") / ("evflow_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

inline void write_file(const std::filesystem::path& path, const uint8_t* data, size_t size) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  f.close();
  if (!f) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

// The input as work_dir() / name.
inline std::filesystem::path input_file(const uint8_t* data, size_t size, const std::string& name) {
  const std::filesystem::path p = work_dir() / name;
  write_file(p, data, size);
  return p;
}

// Runs `read`; a reader's error must name `name`, else the harness aborts (a finding).
template <class F>
void expect_clear_errors(const std::string& name, F&& read) {
  try {
    read();
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).find(name) == std::string::npos) {
      std::fprintf(stderr, "fuzz: error without the file name %s: %s\n", name.c_str(), e.what());
      std::abort();
    }
  } catch (const std::invalid_argument& e) {
    if (std::string(e.what()).find(name) == std::string::npos) {
      std::fprintf(stderr, "fuzz: error without the file name %s: %s\n", name.c_str(), e.what());
      std::abort();
    }
  }
}

}  // namespace evflow::fuzz
