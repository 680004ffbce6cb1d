// What training starts from, taken from the dataset: each view's target image, the events and
// their thresholds, and the initial Gaussians.
#pragma once
#include <memory>
#include <utility>
#include <vector>

#include "events/interval_events.h"
#include "gpu/context.h"
#include "io/dataset.h"
#include "splat/gaussians.h"
#include "train/train_config.h"

namespace evflow {

// The image a training view is fitted to: its blurry input, its sharp ground truth, or the EDI
// estimate at mid-exposure (cfg.target). EDI needs the dataset's events.
io::Image training_target(const io::Dataset& data, size_t view, const TrainConfig& cfg);
// training_target() as the image terms compare it: planar RGB in cfg.loss_space.
std::vector<float> loss_space_target(const io::Dataset& data, size_t view, const TrainConfig& cfg);
// An image as the image terms compare it: planar RGB in cfg.loss_space.
std::vector<float> loss_space_image(const io::Image& image, const TrainConfig& cfg);
// The view's blurry input deblurred by EDI at exposure times u in [0, 1] (0.5: mid-exposure),
// clamped to [0, 1]. Throws naming the dataset or view when it has no events or exposure.
std::vector<io::Image> edi_frames(const io::Dataset& data, size_t view, const TrainConfig& cfg,
                                  const std::vector<double>& times);
// Event thresholds for the event loss / EDI: the config's, else the dataset's (simulator
// manifest), else 0.2.
std::pair<double, double> event_thresholds(const io::Dataset& data, const TrainConfig& cfg);

// The training views' events on the GPU for the event loss, one window per view (its exposure):
// the dataset's event stream (exact counts) or, for a dataset with binned counts only
// (EBAD-NeRF), its bins. Throws naming the dataset when it has neither, when the events' sensor
// differs from the images or when a view has no exposure interval.
std::unique_ptr<IntervalEvents> training_events(gpu::Context& ctx, const io::Dataset& data);

// Per training view, the planes of the warped-event loss (loss/warped_event_loss.h): for each
// interval between consecutive `frame_u` (the exposure's normalised frame times), the events of
// the dataset's stream warped to the interval's end along flows[view][interval] (H * W * 2, as
// train/training_flows.h gives), then the flow's u and v planes (0 where it is not finite).
std::vector<std::vector<float>> warped_event_planes(const io::Dataset& data, const TrainConfig& cfg,
                                                    const std::vector<double>& frame_u,
                                                    const std::vector<std::vector<std::vector<float>>>& flows);
// The same for training view v alone, from its intervals' flows.
std::vector<float> view_warped_event_planes(const io::Dataset& data, const TrainConfig& cfg,
                                            const std::vector<double>& frame_u, size_t v,
                                            const std::vector<std::vector<float>>& flows);

// Random Gaussians inside the training views' frustums between the near and far bounds, coloured
// from the pixel they were seeded on; with init=points, one Gaussian per sparse point of the
// dataset (throws when it has none).
GaussianCloud initial_cloud(const io::Dataset& data, const TrainConfig& cfg);

}  // namespace evflow
