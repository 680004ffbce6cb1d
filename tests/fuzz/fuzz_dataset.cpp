// libFuzzer harness: dataset folders (io::load_dataset) with a fuzzed manifest. The first byte
// picks the layout; the rest becomes its manifest in a folder that otherwise holds a small valid
// dataset (written once per process): dataset.json (ours), transforms_train.json (NeRF
// synthetic) or poses_bounds.npy (LLFF with sharp images).
#include <string>

#include "fuzz_dataset_base.h"
#include "fuzz_input.h"
#include "io/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const evflow::fuzz::DatasetFolders folders = evflow::fuzz::make_dataset_folders();
  const auto& layout = folders.layouts[data[0] % folders.layouts.size()];
  const std::filesystem::path& dir = layout.first;
  evflow::fuzz::write_file(dir / layout.second, data + 1, size - 1);
  // An error may name the manifest or a file it points to: any path in the dataset folder.
  evflow::fuzz::expect_clear_errors(dir.string(), [&] { evflow::io::load_dataset(dir); });
  return 0;
}
