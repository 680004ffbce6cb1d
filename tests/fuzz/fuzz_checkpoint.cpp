// libFuzzer harness: training checkpoints from memory (parse_checkpoint). The checksum would
// stop almost every mutated input at once, so each input is also parsed with its last 4 bytes
// replaced by the correct checksum: the fuzzer reaches the parser behind it.
#include <cstring>
#include <vector>

#include "fuzz_input.h"
#include "io/crc32.h"
#include "train/checkpoint.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  evflow::fuzz::expect_clear_errors("input.ckpt", [&] { evflow::parse_checkpoint("input.ckpt", data, size); });
  if (size < 4) return 0;
  std::vector<uint8_t> sealed(data, data + size);
  const uint32_t crc = evflow::io::crc32(data, size - 4);
  std::memcpy(sealed.data() + size - 4, &crc, 4);
  evflow::fuzz::expect_clear_errors("input.ckpt",
                                    [&] { evflow::parse_checkpoint("input.ckpt", sealed.data(), sealed.size()); });
  return 0;
}
