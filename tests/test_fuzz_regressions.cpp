// Inputs that once crashed a reader under the fuzzer (tests/fuzz/regressions/<harness>/) give a
// clear error in the ordinary build too. scripts/fuzz.sh replays them under the sanitizers.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_helpers.h"
#include "io/dataset.h"
#include "io/events_h5.h"
#include "io/image.h"
#include "io/npy.h"

using namespace evflow;
namespace fs = std::filesystem;
using Catch::Contains;

TEST_CASE("fuzz regressions: an HDF5 event file whose type claims 771,751,938-byte numbers is refused", "[io][fuzz]") {
  const fs::path input =
      fs::path(EVF_SOURCE_DIR) / "tests/fuzz/regressions/h5_events/crash-68751829da9a4a0ed3e0e747d09d26537f5ef451";
  const std::string bytes = test::slurp(input);
  REQUIRE(bytes.size() > 1);
  // The harness's first byte picks the time unit; the HDF5 image follows.
  const fs::path file = fs::temp_directory_path() / ("evf_fuzz_regression_" + std::to_string(::getpid()) + ".h5");
  std::ofstream(file, std::ios::binary) << bytes.substr(1);
  REQUIRE_THROWS_WITH(io::read_events_h5(file), Contains(file.string()) && Contains("corrupt dataset /events/x") &&
                                                    Contains("771751938-byte numbers"));
  REQUIRE_THROWS_WITH(io::read_events_h5_image(bytes.data() + 1, bytes.size() - 1, "image.h5"),
                      Contains("image.h5") && Contains("771751938-byte numbers"));
  fs::remove(file);
}

TEST_CASE("fuzz regressions: an npy shape needing more than 2^64 bytes is refused with that said", "[io][fuzz]") {
  const fs::path input =
      fs::path(EVF_SOURCE_DIR) / "tests/fuzz/regressions/npy/crash-27323ba35d69f3309ba2d98de5bcdadaf4897407";
  REQUIRE(fs::exists(input));
  REQUIRE_THROWS_WITH(io::read_npy(input), Contains(input.filename().string()) &&
                                               Contains("needs more than 18446744073709551615 bytes of data"));
}

TEST_CASE("fuzz regressions: a NeRF-synthetic camera_angle_x that is a string is an error naming the file",
          "[io][fuzz]") {
  const fs::path dir = fs::temp_directory_path() / ("evf_fuzz_nerf_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  io::write_png(dir / "train" / "000.png", io::Image(4, 3, 3, 0.5f));
  std::ofstream(dir / "transforms_train.json")
      << R"({"camera_angle_x": "./train/000.png", "frames": [{"file_path": "./train/000", )"
      << R"("transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}]})";
  REQUIRE_THROWS_WITH(io::load_dataset(dir),
                      Contains((dir / "transforms_train.json").string()) && Contains("type must be number"));
  fs::remove_all(dir);
}

TEST_CASE("fuzz regressions: a NeRF-synthetic frame with an absolute file_path to no image names the manifest",
          "[io][fuzz]") {
  const fs::path dir = fs::temp_directory_path() / ("evf_fuzz_nerf_abs_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  io::write_png(dir / "train" / "001.png", io::Image(4, 3, 3, 0.5f));
  std::ofstream(dir / "transforms_train.json")
      << R"({"camera_angle_x": 0.69, "frames": [{"file_path": "/./train/000", )"
      << R"("transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,4],[0,0,0,1]]}]})";
  REQUIRE_THROWS_WITH(io::load_dataset(dir), Contains((dir / "transforms_train.json").string()) &&
                                                 Contains("frame 0") && Contains("/./train/000.png") &&
                                                 Contains("view image is missing"));
  fs::remove_all(dir);
}
