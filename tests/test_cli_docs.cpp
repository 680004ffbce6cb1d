// docs/ tables that `evflow` prints from its option tables stay equal to what it prints.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>

#include "cli_helpers.h"

using namespace evflow;
namespace fs = std::filesystem;

TEST_CASE("cli: docs/viewer.md lists the --view-* options as evflow train --view-options prints them", "[cli][docs]") {
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path out = fs::temp_directory_path() / "evflow_view_options.md";
  const std::string cmd =
      test::quote(test::evflow_binary().string()) + " train --view-options > " + test::quote(out.string());
  REQUIRE(std::system(cmd.c_str()) == 0);
  const std::string printed = test::slurp(out);
  fs::remove(out);
  INFO("regenerate the table in docs/viewer.md with build/evflow train --view-options");
  CHECK(test::generated_section("viewer.md", "evflow train --view-options") == printed);
}
