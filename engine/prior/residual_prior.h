// The residual prior of a dataset's training views: the residual network's R(t_i) = I(t_i) - I(t_N)
// at the trainer's virtual-frame times, computed once on the device from each view's blurry image
// and the events of its exposure (prior/event_inputs.h).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gpu/context.h"
#include "io/dataset.h"

namespace evflow::prior {

// Where the weights are read: `path` as given when it exists, else, for a relative path, the same
// path under the source tree (so that the default, assets/residual_prior.safetensors, is found
// from any working directory).
std::string resolve_weights_path(const std::string& path);

// Per training view: (u.size() - 1) planar linear-RGB residuals, the non-middle frames in order.
// Throws when the weights' frame count differs from u.size(), the dataset has no events, or the
// weights file is missing or damaged (naming the file).
std::vector<std::vector<float>> predict_residuals(gpu::Context& ctx, const std::string& weights_path,
                                                  const io::Dataset& data, const std::vector<double>& u);

}  // namespace evflow::prior
