// Training and scoring the residual prior's network (prior/residual_net.h) on simulated samples
// (prior/training_samples.h): Adam (eps 1e-8) on the mean squared error of random crops, a batch's
// gradients summed on the device; the held-out score compares the network's residuals with the
// zero residual and the EDI baseline's on whole views.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "prior/residual_net.h"
#include "prior/training_samples.h"

namespace evflow::prior {

struct PriorTrainOptions {
  uint32_t steps = 2000;
  uint32_t crop = 64;  // square crops of this many pixels
  uint32_t batch = 4;  // crops per Adam step
  float lr = 1e-3f;
  uint64_t seed = 1;
  double max_seconds = 0;  // stop earlier when the wall time is up (0: no limit)
};

struct StepLog {
  uint32_t step = 0;
  double loss = 0;  // the batch's mean squared error
  double seconds = 0;
};

// Trains `net` (sized crop x crop) on `samples`; calls `log` after every step. Returns the steps run.
uint32_t train_prior(gpu::Context& ctx, ResidualNet& net, const std::vector<PriorSample>& samples,
                     const PriorTrainOptions& o, const std::function<void(const StepLog&)>& log);

struct ResidualErrors {
  double network = 0, zero = 0, edi = 0;  // mean squared error over every value of every sample
  size_t values = 0;
};

// Scores `weights`' residuals on whole samples (a network of the samples' size is made for it).
ResidualErrors score_prior(gpu::Context& ctx, const ResidualNet& weights, const std::vector<PriorSample>& samples);

}  // namespace evflow::prior
