// libFuzzer harness: NumPy .npy arrays (io::read_npy and the conversion to double).
#include "fuzz_input.h"
#include "io/npy.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = evflow::fuzz::input_file(data, size, "input.npy");
  evflow::fuzz::expect_clear_errors("input.npy", [&] { evflow::io::read_npy(path).to_double(); });
  return 0;
}
