#include "io/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <system_error>

namespace evflow::io {

namespace fs = std::filesystem;

void write_file_atomic(const fs::path& target, const std::function<void(const fs::path& tmp)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(target.string() + ": cannot create folder " + dir.string() + ": " + ec.message());
  std::string name(1, '.');
  name += target.stem().string();
  name += ".tmp";
  name += std::to_string(::getpid());
  name += '-';
  name += std::to_string(counter++);
  name += target.extension().string();
  const fs::path tmp = dir / name;
  try {
    write(tmp);
    if (!fs::is_regular_file(tmp)) throw std::runtime_error(target.string() + ": the writer produced no file");
    fs::rename(tmp, target, ec);
    if (ec)
      throw std::runtime_error(target.string() + ": cannot rename the temporary file into place: " + ec.message());
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace evflow::io
