#include "train/checkpoint.h"

#include <cstring>
#include <fstream>
#include <stdexcept>

#include "io/atomic_file.h"

namespace evflow {

static constexpr char kMagic[8] = {'E', 'V', 'F', 'C', 'K', 'P', 'T', '1'};

void write_checkpoint(const std::filesystem::path& path, const Checkpoint& c) {
  c.cloud.validate("checkpoint " + path.string());
  io::write_file_atomic(path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw std::runtime_error(tmp.string() + ": cannot open for writing");
    const uint64_t n = c.cloud.size();
    const int32_t degree = c.cloud.sh_degree;
    f.write(kMagic, 8);
    f.write(reinterpret_cast<const char*>(&c.step), 4);
    f.write(reinterpret_cast<const char*>(&degree), 4);
    f.write(reinterpret_cast<const char*>(&n), 8);
    for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
      f.write(reinterpret_cast<const char*>(v->data()), std::streamsize(v->size() * 4));
    if (!f) throw std::runtime_error(tmp.string() + ": write failed");
  });
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path.string() + ": cannot open checkpoint");
  char magic[8];
  Checkpoint c;
  int32_t degree = 0;
  uint64_t n = 0;
  f.read(magic, 8);
  if (!f || std::memcmp(magic, kMagic, 8) != 0) throw std::runtime_error(path.string() + ": not an EvFlow checkpoint");
  f.read(reinterpret_cast<char*>(&c.step), 4);
  f.read(reinterpret_cast<char*>(&degree), 4);
  f.read(reinterpret_cast<char*>(&n), 8);
  if (!f || degree < 0 || degree > 3 || n > (1ull << 32))
    throw std::runtime_error(path.string() + ": corrupt checkpoint header");
  const uint64_t expect = 24 + n * 4 * (3 + 3 + 4 + 1 + 3 * uint64_t(sh_coeff_count(degree)));
  if (std::filesystem::file_size(path) != expect)
    throw std::runtime_error(path.string() + ": checkpoint is " + std::to_string(std::filesystem::file_size(path)) +
                             " bytes, expected " + std::to_string(expect) + " (truncated?)");
  c.cloud.resize(n, degree);
  for (auto* v : {&c.cloud.means, &c.cloud.log_scales, &c.cloud.quats, &c.cloud.opacity_logits, &c.cloud.sh})
    f.read(reinterpret_cast<char*>(v->data()), std::streamsize(v->size() * 4));
  if (!f) throw std::runtime_error(path.string() + ": truncated checkpoint");
  c.cloud.validate("checkpoint " + path.string());
  return c;
}

}  // namespace evflow
