#include "train/checkpoint.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "io/atomic_file.h"

namespace evflow {

static constexpr char kMagic[8] = {'E', 'V', 'F', 'C', 'K', 'P', 'T', '4'};

namespace {

template <class T>
void put(std::ofstream& f, const T& v) {
  f.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
void put_floats(std::ofstream& f, const std::vector<float>& v) {
  f.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * 4));
}

struct Reader {
  std::ifstream f;
  std::string name;
  uint64_t left;
  void need(uint64_t bytes, const char* what) {
    if (bytes > left) throw std::runtime_error(name + ": truncated checkpoint (" + what + ")");
    left -= bytes;
  }
  template <class T>
  T get(const char* what) {
    need(sizeof(T), what);
    T v;
    f.read(reinterpret_cast<char*>(&v), sizeof(T));
    return v;
  }
  std::vector<float> floats(uint64_t n, const char* what) {
    if (n > left / 4) throw std::runtime_error(name + ": truncated checkpoint (" + what + ")");
    need(n * 4, what);
    std::vector<float> v(n);
    f.read(reinterpret_cast<char*>(v.data()), std::streamsize(n * 4));
    return v;
  }
};

}  // namespace

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  c.cloud.validate("checkpoint " + path.string());
  for (auto& g : c.optimizer)
    if (g.exp_avg.size() != g.exp_avg_sq.size())
      throw std::invalid_argument("checkpoint " + path.string() + ": optimizer group " + g.name +
                                  " has mismatched moments");
  io::write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw std::runtime_error(tmp.string() + ": cannot open for writing");
    f.write(kMagic, 8);
    put(f, c.step);
    put(f, int32_t(c.cloud.sh_degree));
    put(f, uint64_t(c.cloud.size()));
    for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
      put_floats(f, *v);
    put(f, uint32_t(c.optimizer.size()));
    for (auto& g : c.optimizer) {
      put(f, uint32_t(g.name.size()));
      f.write(g.name.data(), std::streamsize(g.name.size()));
      put(f, g.step);
      put(f, uint64_t(g.exp_avg.size()));
      put_floats(f, g.exp_avg);
      put_floats(f, g.exp_avg_sq);
    }
    put(f, uint32_t(c.trajectories.size()));
    for (auto& t : c.trajectories) {
      const size_t k = t.knots.size();
      if ((k != 54 && k != 6) || t.exp_avg.size() != k || t.exp_avg_sq.size() != k)
        throw std::invalid_argument("checkpoint " + path.string() +
                                    ": a camera state needs 54 (trajectory) or 6 (pose) values and moments");
      put(f, t.step);
      put(f, uint32_t(k));
      for (auto* v : {&t.knots, &t.exp_avg, &t.exp_avg_sq})
        f.write(reinterpret_cast<const char*>(v->data()), std::streamsize(k * 8));
    }
    if (!f) throw std::runtime_error(tmp.string() + ": write failed");
  });
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  Reader r{std::ifstream(path, std::ios::binary), path.string(), 0};
  if (!r.f) throw std::runtime_error(path.string() + ": cannot open checkpoint");
  r.left = std::filesystem::file_size(path);
  char magic[8];
  r.need(8, "magic");
  r.f.read(magic, 8);
  if (std::memcmp(magic, kMagic, 8) != 0)
    throw std::runtime_error(path.string() + ": not an EvFlow checkpoint (version 4)");
  Checkpoint c;
  c.step = r.get<uint32_t>("step");
  const int32_t degree = r.get<int32_t>("SH degree");
  const uint64_t n = r.get<uint64_t>("count");
  if (degree < 0 || degree > 3)
    throw std::runtime_error(path.string() + ": corrupt checkpoint (SH degree " + std::to_string(degree) + ")");
  if (n > r.left / 4)
    throw std::runtime_error(path.string() + ": truncated checkpoint (" + std::to_string(n) + " Gaussians announced)");
  c.cloud.resize(n, degree);
  for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
    *v = r.floats(v->size(), "Gaussians");
  const uint32_t groups = r.get<uint32_t>("optimizer groups");
  if (groups > 64)
    throw std::runtime_error(path.string() + ": corrupt checkpoint (" + std::to_string(groups) + " optimizer groups)");
  for (uint32_t i = 0; i < groups; ++i) {
    OptimizerGroupState g;
    const uint32_t len = r.get<uint32_t>("group name");
    if (len > 256) throw std::runtime_error(path.string() + ": corrupt checkpoint (optimizer group name)");
    r.need(len, "group name");
    g.name.resize(len);
    r.f.read(g.name.data(), len);
    g.step = r.get<uint64_t>("group step");
    const uint64_t count = r.get<uint64_t>("group size");
    g.exp_avg = r.floats(count, "optimizer moments");
    g.exp_avg_sq = r.floats(count, "optimizer moments");
    c.optimizer.push_back(std::move(g));
  }
  const uint32_t trajectories = r.get<uint32_t>("trajectory count");
  if (trajectories > (1u << 20)) throw std::runtime_error(path.string() + ": corrupt checkpoint (trajectory count)");
  for (uint32_t i = 0; i < trajectories; ++i) {
    TrajectoryState t;
    t.step = r.get<uint64_t>("trajectory step");
    const uint32_t k = r.get<uint32_t>("camera state size");
    if (k != 54 && k != 6)
      throw std::runtime_error(path.string() + ": corrupt checkpoint (camera state of " + std::to_string(k) +
                               " values)");
    for (auto* v : {&t.knots, &t.exp_avg, &t.exp_avg_sq}) {
      r.need(size_t(k) * 8, "trajectory");
      v->resize(k);
      r.f.read(reinterpret_cast<char*>(v->data()), std::streamsize(k * 8));
      for (double x : *v)
        if (!std::isfinite(x))
          throw std::runtime_error(path.string() + ": trajectory " + std::to_string(i) + " is not finite");
    }
    c.trajectories.push_back(std::move(t));
  }
  if (!r.f) throw std::runtime_error(path.string() + ": read error");
  if (r.left)
    throw std::runtime_error(path.string() + ": " + std::to_string(r.left) + " unexpected bytes after the checkpoint");
  c.cloud.validate("checkpoint " + path.string());
  return c;
}

}  // namespace evflow
