// A sharp multi-view dataset rendered from a synthetic ground-truth Gaussian cloud: for tests
// and benchmarks of the trainer without files.
#pragma once
#include "gpu/context.h"
#include "io/dataset.h"

namespace evflow {

// `n_train` + `n_novel` views on an arc around a cloud of `gaussians` Gaussians (SH degree 0)
// centred at depth 6 from the first camera; every image is its own sharp ground truth (training
// images are also the `blurry` input). Deterministic for a seed.
io::Dataset render_synthetic_dataset(gpu::Context& ctx, uint32_t width, uint32_t height, int n_train, int n_novel,
                                     size_t gaussians = 1500, uint64_t seed = 42);

}  // namespace evflow
