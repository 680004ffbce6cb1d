// libFuzzer harness: glTF scenes for the simulator (sim::load_gltf and its checks); input that
// starts with the GLB magic is read as .glb, the rest as .gltf.
#include <cstring>

#include "fuzz_input.h"
#include "sim/gltf_scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  const std::string name = glb ? "scene.glb" : "scene.gltf";
  const auto path = evflow::fuzz::input_file(data, size, name);
  evflow::fuzz::expect_clear_errors(name, [&] { evflow::sim::load_gltf(path); });
  return 0;
}
