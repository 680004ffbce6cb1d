// Events in HDF5 files: DSEC layout (/events/{x,y,t,p}, /t_offset) and root-level x, y, t, p
// (EvDeblurNeRF), plus our per-view exposure windows (/exposure/start_us, /exposure/end_us).
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "events/event_stream.h"
#include "io/events_txt.h"  // TimeUnit

namespace evflow::io {

struct H5ReadOptions {
  TimeUnit unit = TimeUnit::us;  // unit of the t datasets (DSEC: us; EvDeblurNeRF Blender: ns)
  // Sensor size; 0 = the /events (or root) attributes "width"/"height" if present, else max + 1.
  uint32_t width = 0, height = 0;
  bool apply_t_offset = true;  // add /t_offset (us) so that times are absolute (DSEC)
};

struct H5Events {
  EventStream events;                                // t in seconds
  std::vector<double> exposure_start, exposure_end;  // seconds, same clock as events; may be empty
  int64_t t_offset_us = 0;                           // /t_offset as stored (0 when absent)
};

// Reads /events/{x,y,t,p} or, failing that, root-level x, y, t, p, each a 1-D dataset of any
// integer or float type; polarity > 0 is positive, 0 or -1 negative. Throws std::runtime_error
// naming the file on a missing/truncated/corrupt file, missing datasets, a count mismatch, a
// non-integer or negative coordinate, a bad polarity, unsorted timestamps, an event outside the
// sensor, or a compression filter that is not installed (Blosc: names the Debian package).
// HDF5's own error printing is silenced.
H5Events read_events_h5(const std::filesystem::path& path, const H5ReadOptions& options = {});
// The same from a file image in memory (HDF5's core driver, nothing written); `name` names it
// in errors.
H5Events read_events_h5_image(const void* data, size_t size, const std::string& name,
                              const H5ReadOptions& options = {});

struct H5WriteOptions {
  int64_t t_offset_us = 0;  // stored as /t_offset; /events/t and /exposure/* are relative to it
  int deflate_level = 1;    // 0 = no compression; otherwise shuffle + deflate (zlib, built into HDF5)
};

// Writes DSEC style: /events/x, /events/y (uint16), /events/t (int64 us, rounded to the nearest
// microsecond), /events/p (uint8 0/1), /events attributes width/height (uint32), /t_offset
// (int64 us), /ms_to_idx (uint64, DSEC: first event index of each millisecond), and when given
// /exposure/start_us, /exposure/end_us (int64 us). Atomic. Events whose times are whole
// microseconds (t = k / 1e6) read back bit-exactly.
void write_events_h5(const std::filesystem::path& path, const EventStream& events,
                     const std::vector<double>& exposure_start = {}, const std::vector<double>& exposure_end = {},
                     const H5WriteOptions& options = {});

// True when HDF5 can use the Blosc filter (id 32001), i.e. DSEC files can be read.
bool h5_blosc_available();

}  // namespace evflow::io
