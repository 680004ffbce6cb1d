// libFuzzer harness: events as text (io::read_events_txt); the first byte picks the time unit
// and the polarity coding.
#include "fuzz_input.h"
#include "io/events_txt.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  evflow::io::TxtReadOptions opt;
  opt.unit = evflow::io::TimeUnit(data[0] % 4);
  opt.polarity = evflow::io::PolarityCoding((data[0] >> 2) % 3);
  const auto path = evflow::fuzz::input_file(data + 1, size - 1, "events.txt");
  evflow::fuzz::expect_clear_errors("events.txt", [&] { evflow::io::read_events_txt(path, opt); });
  return 0;
}
