// The optical flow of each training view's exposure intervals, for the warped-event loss: from
// the view's events (contrast maximisation, flow/flow_estimator.h; cached on disk) or from the
// simulator's ground truth (flow=gt, for ablations).
#pragma once
#include <string>
#include <vector>

#include "gpu/context.h"
#include "io/dataset.h"
#include "train/train_config.h"

namespace evflow {

// Per training view, per interval between consecutive `frame_u` (the virtual frames' normalised
// times): the displacement over the interval at every pixel, H * W * 2 (u, v; NaN where the
// ground truth has no surface). Throws naming the dataset when the source is missing (no event
// stream with times; flow=gt without gt/trajectories.json and gt/depth/).
std::vector<std::vector<std::vector<float>>> training_flows(gpu::Context& ctx, const io::Dataset& data,
                                                            FlowSource source, const std::vector<double>& frame_u);

// Appends a displacement field d (H * W * 2, u and v interleaved) to `out` as two planes, u then
// v, with 0 where d is not finite: the layout the GPU kernels read.
void append_displacement_planes(const std::vector<float>& d, std::vector<float>& out);

// Where flow=events keeps view `name`'s estimate: DATA/.evflow-cache/flow/<name>-<key>.npy, the key a
// hash of the view's events, the frame times and the estimator's settings (a changed input is a
// new file, never a stale hit).
std::string flow_cache_path(const io::Dataset& data, size_t view, const std::vector<double>& frame_u);
// Keeps an estimate there (`evflow flow` fills the cache this way); a folder that cannot be
// written gets one line on stderr, not an error.
void store_cached_flow(const io::Dataset& data, size_t view, const std::vector<double>& frame_u,
                       const std::vector<std::vector<float>>& flows);

}  // namespace evflow
