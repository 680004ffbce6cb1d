// Events as text, one event per line: `t x y p` (rpg / v2e / E3NeRF style).
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "events/event_stream.h"

namespace evflow::io {

enum class TimeUnit { s, ms, us, ns };
double seconds_per(TimeUnit u);                // 1, 1e-3, 1e-6, 1e-9
TimeUnit parse_time_unit(const std::string&);  // "s", "ms", "us", "ns"; throws std::invalid_argument
std::string to_string(TimeUnit u);

enum class PolarityCoding {
  zero_one,          // 0 = negative, 1 = positive (rpg, v2e); other values are an error
  minus_one_one,     // -1 = negative, 1 = positive; other values are an error
  one_else_negative  // 1 = positive, any other number negative (E3NeRF's loader)
};

struct TxtReadOptions {
  TimeUnit unit = TimeUnit::s;
  PolarityCoding polarity = PolarityCoding::zero_one;
  // Sensor size; 0 = take it from a "W H" header line, else from the largest x, y + 1.
  uint32_t width = 0, height = 0;
};

struct TxtWriteOptions {
  TimeUnit unit = TimeUnit::s;
  PolarityCoding polarity = PolarityCoding::zero_one;  // one_else_negative writes 1 / 0
  bool header = true;                                  // first line "W H" (sensor size)
};

// Blank lines and lines starting with '#' are skipped. The first data line may be a header of
// exactly two integers, the sensor size "W H" (a size given in the options wins). Timestamps
// are converted to seconds by shifting the decimal point of the text (so "1234567" us reads as
// the double nearest 1.234567 s). Throws std::runtime_error naming the file and the line
// number on a malformed line, a bad polarity or a negative/overlarge coordinate, and naming the
// file on unsorted timestamps or events outside the sensor (EventStream::validate).
EventStream read_events_txt(const std::filesystem::path& path, const TxtReadOptions& options = {});
// Writes atomically. Timestamps are written as the shortest decimal that reads back as the same
// double, scaled to `unit` by moving the decimal point: write -> read round trips are exact.
void write_events_txt(const std::filesystem::path& path, const EventStream& events,
                      const TxtWriteOptions& options = {});

}  // namespace evflow::io
