// What the event loss reads: for each training view, the per-pixel positive and negative event
// amounts of a time interval, recorded into a plane of a counts buffer on the GPU. Two sources:
// GpuEvents (an event stream: integer counts, exact) and BinnedEvents (per-view binned signed
// counts: fractional amounts where an interval covers part of a bin).
#pragma once
#include <cstddef>
#include <cstdint>

#include "gpu/buffer.h"
#include "gpu/commands.h"

namespace evflow {

class IntervalEvents {
 public:
  virtual ~IntervalEvents() = default;
  virtual uint32_t width() const = 0;
  virtual uint32_t height() const = 0;
  virtual size_t window_count() const = 0;  // one window per training view
  // Whether a plane's 32-bit values are floats (amounts) rather than uints (counts).
  virtual bool float_planes() const = 0;
  // Records view w's positive / negative amounts in [t0, t1) into plane `plane` of `counts`
  // (2 * H * W values per plane: [positive H*W][negative H*W]; added to what is there: clear it
  // first, a zero fill being 0 in both number types).
  virtual void accumulate(gpu::Commands& cmd, size_t w, double t0, double t1, const gpu::Buffer& counts,
                          uint32_t plane) const = 0;
  // Changes whenever accumulate() would record other amounts for the same arguments (a source
  // over a crop that moved): a cache of counts keyed by view and times compares it too.
  virtual uint64_t generation() const { return 0; }
};

}  // namespace evflow
