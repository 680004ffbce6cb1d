// The reductions the normalised event losses share: loss/reduce adds the per-group partials
// (sum of measured * predicted, predicted^2, measured^2) of one pair or interval into its slot
// sums[dst .. dst + 2].
#pragma once
#include <cstdint>

#include "gpu/commands.h"

namespace evflow {

void record_event_sums(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                       uint32_t dst);
// Every column c < columns of n_partials vec4 partials (partials[c * n_partials + g]) into
// sums[4 c .. 4 c + 3], a workgroup each: the one-pass event pairs' five sums a pair.
void record_event_columns(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                          uint32_t columns);

}  // namespace evflow
