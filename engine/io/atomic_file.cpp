#include "io/atomic_file.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

namespace evflow::io {

namespace fs = std::filesystem;

namespace {

// Built by appending: GCC 12 warns falsely (-Wrestrict) on "." + std::string.
std::string hidden(const std::string& name, const char* suffix) {
  std::string s(1, '.');
  s += name;
  s += suffix;
  return s;
}

std::string temporary_prefix(const fs::path& target) { return hidden(target.stem().string(), ".tmp"); }

// The writer's process id when `name` is one of target's temporaries, else 0.
pid_t temporary_owner(const std::string& name, const fs::path& target) {
  const std::string prefix = temporary_prefix(target), ext = target.extension().string();
  if (name.size() <= prefix.size() + ext.size() || name.rfind(prefix, 0) != 0) return 0;
  if (name.compare(name.size() - ext.size(), ext.size(), ext) != 0) return 0;
  const std::string middle = name.substr(prefix.size(), name.size() - prefix.size() - ext.size());
  const size_t dash = middle.find('-');
  if (dash == 0 || dash == std::string::npos || dash > 9) return 0;
  for (size_t i = 0; i < middle.size(); ++i)
    if (i != dash && (middle[i] < '0' || middle[i] > '9')) return 0;
  return pid_t(std::stol(middle.substr(0, dash)));
}

}  // namespace

void write_file_atomic(const fs::path& target, const std::function<void(const fs::path& tmp)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(target.string() + ": cannot create folder " + dir.string() + ": " + ec.message());
  std::string name = temporary_prefix(target);
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

void write_folder_atomic(const fs::path& target, const std::string& marker,
                         const std::function<void(const fs::path& stage)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path clean = target.lexically_normal();
  const fs::path name = clean.has_filename() ? clean.filename() : clean.parent_path().filename();
  if (name.empty() || name == "." || name == "..")
    throw std::runtime_error(target.string() + ": name the output folder itself (not . or /)");
  const fs::path parent = fs::absolute(clean).parent_path();
  const fs::path dest = parent / name;
  std::error_code ec;
  if (fs::exists(dest) && !fs::is_empty(dest) && !fs::exists(dest / marker))
    throw std::runtime_error(target.string() + ": exists and holds no " + marker + "; refusing to replace it");
  std::string tag = std::to_string(::getpid());
  tag += '-';
  tag += std::to_string(counter++);
  const fs::path stage = parent / (hidden(name.string(), ".tmp") + tag),
                 old = parent / (hidden(name.string(), ".old") + tag);
  auto undo = [&] {
    fs::remove_all(stage, ec);
    if (!fs::exists(dest) && fs::exists(old)) fs::rename(old, dest, ec);
  };
  try {
    fs::create_directories(stage);
    write(stage);
    if (fs::exists(dest)) fs::rename(dest, old);
    fs::rename(stage, dest);
  } catch (const std::runtime_error& e) {  // errors name the stage's files: say what became of target
    undo();
    throw std::runtime_error(target.string() + " not written (" +
                             (fs::exists(dest) ? "kept as it was" : "not created") + "): " + e.what());
  } catch (...) {
    undo();
    throw;
  }
  fs::remove_all(old, ec);
}

void close_or_throw(std::ofstream& f, const fs::path& target) {
  // errno still holds the failed write's reason: closing a stream does not clear it.
  if (f.is_open()) f.close();
  if (f) return;
  const std::string why = errno ? std::strerror(errno) : "unknown error";
  throw std::runtime_error(target.string() + ": write failed (" + why + ")");
}

int remove_stale_temporaries(const fs::path& target) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  int removed = 0;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const pid_t owner = temporary_owner(e.path().filename().string(), target);
    if (owner <= 0 || owner == ::getpid()) continue;
    if (::kill(owner, 0) == 0 || errno == EPERM) continue;  // its writer still runs
    if (fs::remove(e.path(), ec)) ++removed;
  }
  return removed;
}

}  // namespace evflow::io
