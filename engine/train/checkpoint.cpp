#include "train/checkpoint.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "io/atomic_file.h"
#include "io/crc32.h"

namespace evflow {

// Version 5 is version 4's layout followed by the CRC-32 of everything before it; version 6 is
// version 5 with each camera state followed by its mid-exposure pose's Adam (edi_mid_lr).
static constexpr char kMagic6[8] = {'E', 'V', 'F', 'C', 'K', 'P', 'T', '6'};
static constexpr char kMagic5[8] = {'E', 'V', 'F', 'C', 'K', 'P', 'T', '5'};
static constexpr char kMagic4[8] = {'E', 'V', 'F', 'C', 'K', 'P', 'T', '4'};

namespace {

struct Writer {
  std::string bytes;
  template <class T>
  void put(const T& v) {
    bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <class T>
  void put_all(const std::vector<T>& v) {
    bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
};

struct Reader {
  const uint8_t* p;
  uint64_t left;
  const std::string& name;
  [[noreturn]] void corrupt(const std::string& what) const {
    throw std::runtime_error(name + ": corrupt checkpoint (" + what + ")");
  }
  void need(uint64_t bytes, const char* what) const {
    if (bytes > left) throw std::runtime_error(name + ": truncated checkpoint (" + what + ")");
  }
  void take(void* out, uint64_t bytes, const char* what) {
    need(bytes, what);
    if (bytes) std::memcpy(out, p, bytes);
    p += bytes;
    left -= bytes;
  }
  template <class T>
  T get(const char* what) {
    T v;
    take(&v, sizeof(T), what);
    return v;
  }
  template <class T>
  std::vector<T> array(uint64_t n, const char* what) {
    if (n > left / sizeof(T)) throw std::runtime_error(name + ": truncated checkpoint (" + what + ")");
    std::vector<T> v(n);
    take(v.data(), n * sizeof(T), what);
    return v;
  }
};

void check_writable(const std::filesystem::path& path, const Checkpoint& c) {
  c.cloud.validate("checkpoint " + path.string());
  for (auto& g : c.optimizer)
    if (g.exp_avg.size() != g.exp_avg_sq.size())
      throw std::invalid_argument("checkpoint " + path.string() + ": optimizer group " + g.name +
                                  " has mismatched moments");
  for (auto& t : c.trajectories) {
    const size_t k = t.knots.size();
    if ((k != 54 && k != 6) || t.exp_avg.size() != k || t.exp_avg_sq.size() != k)
      throw std::invalid_argument("checkpoint " + path.string() +
                                  ": a camera state needs 54 (trajectory) or 6 (pose) values and moments");
    const size_t m = t.mid_exp_avg.size();
    if ((m != 0 && m != 6) || t.mid_exp_avg_sq.size() != m)
      throw std::invalid_argument("checkpoint " + path.string() + ": a mid-exposure pose's moments need 0 or 6 values");
  }
}

std::string serialize(const Checkpoint& c) {
  Writer w;
  w.bytes.append(kMagic6, 8);
  w.put(c.step);
  w.put(int32_t(c.cloud.sh_degree));
  w.put(uint64_t(c.cloud.size()));
  for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
    w.put_all(*v);
  w.put(uint32_t(c.optimizer.size()));
  for (auto& g : c.optimizer) {
    w.put(uint32_t(g.name.size()));
    w.bytes += g.name;
    w.put(g.step);
    w.put(uint64_t(g.exp_avg.size()));
    w.put_all(g.exp_avg);
    w.put_all(g.exp_avg_sq);
  }
  w.put(uint32_t(c.trajectories.size()));
  for (auto& t : c.trajectories) {
    w.put(t.step);
    w.put(uint32_t(t.knots.size()));
    for (auto* v : {&t.knots, &t.exp_avg, &t.exp_avg_sq}) w.put_all(*v);
    w.put(uint32_t(t.mid_exp_avg.size()));
    if (t.mid_exp_avg.empty()) continue;
    w.put(t.mid_step);
    for (auto* v : {&t.mid_exp_avg, &t.mid_exp_avg_sq}) w.put_all(*v);
  }
  w.put(io::crc32(w.bytes.data(), w.bytes.size()));
  return std::move(w.bytes);
}

void read_cloud(Reader& r, Checkpoint& c) {
  c.step = r.get<uint32_t>("step");
  const int32_t degree = r.get<int32_t>("SH degree");
  const uint64_t n = r.get<uint64_t>("count");
  if (degree < 0 || degree > 3) r.corrupt("SH degree " + std::to_string(degree));
  if (n > r.left / 4)
    throw std::runtime_error(r.name + ": truncated checkpoint (" + std::to_string(n) + " Gaussians announced)");
  const uint64_t per = 3 + 3 + 4 + 1 + 3 * uint64_t(degree + 1) * uint64_t(degree + 1);
  r.need(n * per * 4, "Gaussians");
  c.cloud.resize(n, degree);
  for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
    *v = r.array<float>(v->size(), "Gaussians");
}

void read_optimizer(Reader& r, Checkpoint& c) {
  const uint32_t groups = r.get<uint32_t>("optimizer groups");
  if (groups > 64) r.corrupt(std::to_string(groups) + " optimizer groups");
  for (uint32_t i = 0; i < groups; ++i) {
    OptimizerGroupState g;
    const uint32_t len = r.get<uint32_t>("group name");
    if (len > 256) r.corrupt("optimizer group name");
    g.name.resize(len);
    r.take(g.name.data(), len, "group name");
    g.step = r.get<uint64_t>("group step");
    const uint64_t count = r.get<uint64_t>("group size");
    g.exp_avg = r.array<float>(count, "optimizer moments");
    g.exp_avg_sq = r.array<float>(count, "optimizer moments");
    c.optimizer.push_back(std::move(g));
  }
}

std::vector<double> finite_doubles(Reader& r, uint64_t n, uint32_t camera) {
  std::vector<double> v = r.array<double>(n, "trajectory");
  for (double x : v)
    if (!std::isfinite(x))
      throw std::runtime_error(r.name + ": trajectory " + std::to_string(camera) + " is not finite");
  return v;
}

// Version 6: the camera state's mid-exposure pose's Adam, 0 or 6 moments each.
void read_mid_moments(Reader& r, TrajectoryState& t, uint32_t camera) {
  const uint32_t m = r.get<uint32_t>("mid pose moments size");
  if (m != 0 && m != 6) r.corrupt("mid pose moments of " + std::to_string(m) + " values");
  if (m == 0) return;
  t.mid_step = r.get<uint64_t>("mid pose step");
  t.mid_exp_avg = finite_doubles(r, m, camera);
  t.mid_exp_avg_sq = finite_doubles(r, m, camera);
}

void read_trajectories(Reader& r, Checkpoint& c, bool mid_moments) {
  const uint32_t trajectories = r.get<uint32_t>("trajectory count");
  if (trajectories > (1u << 20)) r.corrupt("trajectory count");
  for (uint32_t i = 0; i < trajectories; ++i) {
    TrajectoryState t;
    t.step = r.get<uint64_t>("trajectory step");
    const uint32_t k = r.get<uint32_t>("camera state size");
    if (k != 54 && k != 6) r.corrupt("camera state of " + std::to_string(k) + " values");
    for (auto* v : {&t.knots, &t.exp_avg, &t.exp_avg_sq}) *v = finite_doubles(r, k, i);
    if (mid_moments) read_mid_moments(r, t, i);
    c.trajectories.push_back(std::move(t));
  }
}

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  check_writable(path, c);
  const std::string bytes = serialize(c);
  io::write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    io::close_or_throw(f, path);
  });
}

Checkpoint parse_checkpoint(const std::string& name, const uint8_t* data, size_t size) {
  Reader r{data, size, name};
  char magic[8];
  r.take(magic, 8, "magic");
  const bool v6 = std::memcmp(magic, kMagic6, 8) == 0;
  const bool v5 = std::memcmp(magic, kMagic5, 8) == 0;
  if (!v6 && !v5 && std::memcmp(magic, kMagic4, 8) != 0)
    throw std::runtime_error(name + ": not an EvFlow checkpoint (version 4, 5 or 6)");
  if (v6 || v5) {
    r.need(4, "checksum");
    uint32_t stored;
    std::memcpy(&stored, data + size - 4, 4);
    if (io::crc32(data, size - 4) != stored)
      throw std::runtime_error(name + ": checkpoint checksum mismatch (the file is damaged or truncated)");
    r.left -= 4;
  }
  Checkpoint c;
  read_cloud(r, c);
  read_optimizer(r, c);
  read_trajectories(r, c, v6);
  if (r.left) throw std::runtime_error(name + ": " + std::to_string(r.left) + " unexpected bytes after the checkpoint");
  c.cloud.validate("checkpoint " + name);
  return c;
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path.string() + ": cannot open checkpoint");
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw std::runtime_error(path.string() + ": cannot read checkpoint: " + ec.message());
  std::vector<uint8_t> bytes(size);
  f.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size));
  if (!f || f.gcount() != std::streamsize(size)) throw std::runtime_error(path.string() + ": read error");
  return parse_checkpoint(path.string(), bytes.data(), bytes.size());
}

}  // namespace evflow
