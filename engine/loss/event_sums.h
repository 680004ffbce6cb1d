// The reduction both normalised event losses share: loss/reduce adds the per-group partials
// (sum of measured * predicted, predicted^2, measured^2) of one pair or interval into its slot
// sums[dst .. dst + 2].
#pragma once
#include <cstdint>

#include "gpu/commands.h"

namespace evflow {

void record_event_sums(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                       uint32_t dst);

}  // namespace evflow
