// Damaged checkpoints (flipped bits, cut short, grown) are refused; the files a killed run leaves
// (a temporary checkpoint, a half-written curve row) are cleaned up by the next run; a folder
// written atomically replaces the old one whole or not at all.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.h"
#include "io/atomic_file.h"
#include "io/crc32.h"
#include "resume_files.h"
#include "splat/synthetic.h"
#include "train/checkpoint.h"

using namespace evflow;
namespace fs = std::filesystem;
using Catch::Contains;
using evflow::test::fresh_dir;

namespace {

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

Checkpoint small_checkpoint() {
  Checkpoint c;
  c.step = 31;
  c.cloud = synthetic_cloud(9, 12, 1, Camera::look_at(64, 48, 60.0, {0, 0, 0}, {0, 0, 1}, {0, -1, 0}));
  c.optimizer.push_back({"means", 31, std::vector<float>(36, 0.5f), std::vector<float>(36, 0.25f)});
  c.trajectories.push_back({31, std::vector<double>(6, 0.01), std::vector<double>(6, 0.0), std::vector<double>(6, 1)});
  return c;
}

}  // namespace

TEST_CASE("crc32 matches the standard check value", "[checkpoint]") {
  REQUIRE(io::crc32("123456789", 9) == 0xCBF43926u);
  REQUIRE(io::crc32("", 0) == 0u);
  REQUIRE(io::crc32("56789", 5, io::crc32("1234", 4)) == 0xCBF43926u);
}

TEST_CASE("checkpoints: a flipped bit in any byte, a cut and a grown file are refused with the file's name",
          "[checkpoint]") {
  const fs::path dir = fresh_dir("evf_ckpt_damage");
  write_checkpoint(dir / "a.ckpt", small_checkpoint());
  const std::string good = test::slurp(dir / "a.ckpt");
  REQUIRE(read_checkpoint(dir / "a.ckpt").trajectories.size() == 1);
  size_t refused = 0;
  for (size_t byte = 0; byte < good.size(); ++byte) {
    std::string bad = good;
    bad[byte] = char(bad[byte] ^ (1 << (byte % 8)));
    INFO("bit " << byte % 8 << " of byte " << byte << " of " << good.size());
    REQUIRE_THROWS_WITH(parse_checkpoint("b.ckpt", reinterpret_cast<const uint8_t*>(bad.data()), bad.size()),
                        Contains("b.ckpt"));
    ++refused;
  }
  REQUIRE(refused == good.size());
  for (size_t cut : {size_t(1), size_t(4), good.size() / 2, good.size() - 8}) {
    write_bytes(dir / "cut.ckpt", good.substr(0, good.size() - cut));
    REQUIRE_THROWS_WITH(read_checkpoint(dir / "cut.ckpt"), Contains("cut.ckpt") && Contains("truncated"));
  }
  write_bytes(dir / "grown.ckpt", good + std::string(4, '\0'));
  REQUIRE_THROWS_WITH(read_checkpoint(dir / "grown.ckpt"), Contains("grown.ckpt") && Contains("checksum"));
  write_bytes(dir / "empty.ckpt", "");
  REQUIRE_THROWS_WITH(read_checkpoint(dir / "empty.ckpt"), Contains("empty.ckpt") && Contains("truncated"));
  fs::remove_all(dir);
}

TEST_CASE("checkpoints: the mid-exposure pose's moments round-trip, and versions 4 and 5 are still read",
          "[checkpoint]") {
  const fs::path dir = fresh_dir("evf_ckpt_v4");
  Checkpoint c = small_checkpoint();
  TrajectoryState moving = c.trajectories[0];
  moving.mid_step = 12;
  moving.mid_exp_avg = {1e-3, -2e-3, 3e-3, 0, 5e-4, -1e-4};
  moving.mid_exp_avg_sq = std::vector<double>(6, 4e-6);
  c.trajectories.push_back(moving);
  write_checkpoint(dir / "v6.ckpt", c);
  const Checkpoint r6 = read_checkpoint(dir / "v6.ckpt");
  REQUIRE(r6.trajectories.size() == 2);
  CHECK(r6.trajectories[0].mid_exp_avg.empty());
  CHECK(r6.trajectories[1].mid_step == 12);
  CHECK(r6.trajectories[1].mid_exp_avg == moving.mid_exp_avg);
  CHECK(r6.trajectories[1].mid_exp_avg_sq == moving.mid_exp_avg_sq);
  moving.mid_exp_avg_sq.pop_back();
  c.trajectories[1] = moving;
  CHECK_THROWS_WITH(write_checkpoint(dir / "bad.ckpt", c), Contains("bad.ckpt") && Contains("mid-exposure"));
  // Without mid moments, version 6 is version 5 with a zero count after each camera state (the
  // last one: before the checksum), and version 5 is version 4 followed by the checksum.
  c.trajectories.pop_back();
  write_checkpoint(dir / "v6.ckpt", c);
  std::string v5 = test::slurp(dir / "v6.ckpt");
  REQUIRE(v5.compare(v5.size() - 8, 4, std::string(4, '\0')) == 0);
  v5.erase(v5.size() - 8, 4);
  v5[7] = '5';
  const uint32_t crc = io::crc32(v5.data(), v5.size() - 4);
  std::memcpy(v5.data() + v5.size() - 4, &crc, 4);
  std::string v4 = v5.substr(0, v5.size() - 4);
  v4[7] = '4';
  for (const auto& [name, bytes] : {std::pair{"v5.ckpt", v5}, std::pair{"v4.ckpt", v4}}) {
    INFO(name);
    write_bytes(dir / name, bytes);
    const Checkpoint r = read_checkpoint(dir / name);
    REQUIRE(r.step == c.step);
    REQUIRE(r.cloud.means == c.cloud.means);
    REQUIRE(r.optimizer[0].exp_avg_sq == c.optimizer[0].exp_avg_sq);
    REQUIRE(r.trajectories[0].knots == c.trajectories[0].knots);
    REQUIRE(r.trajectories[0].mid_exp_avg.empty());
  }
  v4[7] = '3';
  write_bytes(dir / "v3.ckpt", v4);
  REQUIRE_THROWS_WITH(read_checkpoint(dir / "v3.ckpt"), Contains("v3.ckpt") && Contains("not an EvFlow checkpoint"));
  fs::remove_all(dir);
}

TEST_CASE("a killed writer's temporaries are removed, a running writer's kept", "[checkpoint]") {
  const fs::path dir = fresh_dir("evf_stale_tmp");
  const fs::path target = dir / "checkpoint.ckpt";
  // A process id that is not running: a child that has exited and been reaped.
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  int status = 0;
  ::waitpid(gone, &status, 0);
  const std::string dead = ".checkpoint.tmp" + std::to_string(gone) + "-3.ckpt";
  const std::string alive = ".checkpoint.tmp" + std::to_string(::getppid()) + "-0.ckpt";
  for (const std::string& n : {dead, alive, std::string(".checkpoint.tmpx-1.ckpt"), std::string("other.ckpt")})
    write_bytes(dir / n, "half");
  REQUIRE(io::remove_stale_temporaries(target) == 1);
  CHECK(!fs::exists(dir / dead));
  CHECK(fs::exists(dir / alive));
  CHECK(fs::exists(dir / ".checkpoint.tmpx-1.ckpt"));
  CHECK(fs::exists(dir / "other.ckpt"));
  fs::remove_all(dir);
}

TEST_CASE("resume trims curve.csv to the checkpoint's step and drops a half-written row", "[checkpoint]") {
  const fs::path dir = fresh_dir("evf_trim_curve");
  const std::string head = "step,view,loss\n1,0,0.5\n2,1,0.4\n3,2,0.3\n";
  write_bytes(dir / "curve.csv", head + "4,0,0.2\n5,1,0.");
  app::trim_curve(dir / "curve.csv", 3);
  REQUIRE(test::slurp(dir / "curve.csv") == head);
  write_bytes(dir / "curve.csv", head + "4,0,0");
  app::trim_curve(dir / "curve.csv", 9);
  REQUIRE(test::slurp(dir / "curve.csv") == head);
  app::trim_curve(dir / "curve.csv", 0);
  REQUIRE(test::slurp(dir / "curve.csv") == "step,view,loss\n");
  app::trim_curve(dir / "missing.csv", 3);
  REQUIRE(!fs::exists(dir / "missing.csv"));
  fs::remove_all(dir);
}

TEST_CASE("a folder written atomically replaces the old one whole, or not at all", "[checkpoint]") {
  const fs::path dir = fresh_dir("evf_folder_atomic");
  auto fill = [](const std::string& text) {
    return [text](const fs::path& stage) {
      write_bytes(stage / "dataset.json", text);
      write_bytes(stage / "a.txt", text);
    };
  };
  io::write_folder_atomic(dir / "out", "dataset.json", fill("one"));
  write_bytes(dir / "out" / "stale.txt", "from before");
  io::write_folder_atomic(dir / "out", "dataset.json", fill("two"));
  CHECK(test::slurp(dir / "out" / "a.txt") == "two");
  CHECK(!fs::exists(dir / "out" / "stale.txt"));  // the old folder went as a whole
  REQUIRE_THROWS_WITH(io::write_folder_atomic(dir / "out", "dataset.json",
                                              [](const fs::path& stage) {
                                                write_bytes(stage / "a.txt", "half");
                                                throw std::runtime_error("disk full");
                                              }),
                      Contains("out not written (kept as it was)") && Contains("disk full"));
  CHECK(test::slurp(dir / "out" / "a.txt") == "two");
  fs::create_directories(dir / "home");
  write_bytes(dir / "home" / "notes.txt", "keep");
  REQUIRE_THROWS_WITH(io::write_folder_atomic(dir / "home", "dataset.json", fill("x")),
                      Contains("home") && Contains("refusing to replace it"));
  CHECK(test::slurp(dir / "home" / "notes.txt") == "keep");
  size_t entries = 0;
  for (auto& e : fs::directory_iterator(dir)) entries += e.path().filename().string()[0] == '.';
  CHECK(entries == 0);  // no stage or old folder left
  fs::remove_all(dir);
}
