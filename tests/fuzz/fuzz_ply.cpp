// libFuzzer harness: Inria-layout PLY splats (io::read_ply).
#include "fuzz_input.h"
#include "io/ply_splats.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = evflow::fuzz::input_file(data, size, "input.ply");
  evflow::fuzz::expect_clear_errors("input.ply", [&] { evflow::io::read_ply(path); });
  return 0;
}
