// libFuzzer harness: safetensors weight files (nn::load_safetensors).
#include "fuzz_input.h"
#include "nn/safetensors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = evflow::fuzz::input_file(data, size, "input.safetensors");
  evflow::fuzz::expect_clear_errors("input.safetensors", [&] { evflow::nn::load_safetensors(path); });
  return 0;
}
