// libFuzzer harness: HDF5 event files read from an in-memory file image
// (io::read_events_h5_image); the first byte picks the time unit.
#include "fuzz_input.h"
#include "io/events_h5.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  evflow::io::H5ReadOptions opt;
  opt.unit = evflow::io::TimeUnit(data[0] % 4);
  opt.apply_t_offset = data[0] & 4;
  evflow::fuzz::expect_clear_errors("events.h5",
                                    [&] { evflow::io::read_events_h5_image(data + 1, size - 1, "events.h5", opt); });
  return 0;
}
