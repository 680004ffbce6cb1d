// libFuzzer harness: glTF / GLB splats with KHR_gaussian_splatting (io::read_gltf_splats).
#include "fuzz_input.h"
#include "io/gltf_splats.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = evflow::fuzz::input_file(data, size, "input.glb");
  evflow::fuzz::expect_clear_errors("input.glb", [&] { evflow::io::read_gltf_splats(path); });
  return 0;
}
