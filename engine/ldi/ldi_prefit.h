// Initialisation of the LDI to EDI (docs/ldi.md): before joint training, a short Adam regression
// of the network's double integral to EDI's constant-threshold one (events/edi.h, the paper's
// Eq. 3 with the dataset's nominal thresholds) on the training views' events. Each step takes the
// next view (in turn), a random crop of the model's size and `frames` random times t_i in the
// exposure, and minimises the mean of (log E_ldi(t_i) - log E_edi(t_i))^2 over the crop.
// Regressing log E weighs relative errors alike: the frame C = B / E is off by the same factor.
#pragma once
#include <cstdint>
#include <vector>

#include "events/edi.h"
#include "events/event_stream.h"
#include "events/gpu_events.h"
#include "ldi/ldi_model.h"

namespace evflow::ldi {

struct PrefitOptions {
  uint32_t steps = 0;
  uint32_t frames = 1;  // frame times per step (at most the model's max_frames)
  float lr = 1e-3f;
  uint64_t seed = 0;
  events::EdiThresholds thresholds;
};

struct PrefitReport {
  uint32_t steps = 0;
  double first_loss = 0, last_loss = 0;  // the regression's value at the first and last step
};

// `stream` and `events` hold the same events; events' windows are the training views' exposures.
PrefitReport prefit_to_edi(gpu::Context& ctx, LdiModel& model, const EventStream& stream, const GpuEvents& events,
                           const PrefitOptions& options);

}  // namespace evflow::ldi
