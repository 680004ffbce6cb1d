// The EDI warm-up of a blur-mode run (edi_warmup > 0): for its first steps, each step fits one
// render, the view's trajectory at mid-exposure (u = 0.5), to the view's EDI image (the blurry
// input deblurred by EDI with the dataset's events and thresholds), as the 3DGS+EDI baseline
// does. A step of it costs one render instead of 2N+1, so the splats reach the scene's shape
// and colours for a fraction of the blur steps' time; the blur model and its terms then refine
// what EDI gets wrong. The mid-exposure pose gradient moves the trajectory as a whole.
// With edi_warmup_motion, the warm-up's first steps fit one of the 2N+1 virtual frames each, to
// EDI at that frame's time (EDI deblurs to any time of the exposure): the knots learn the
// motion, from a scene still coarse enough to guide them, before the blur steps start.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "gpu/buffer.h"
#include "io/dataset.h"
#include "train/exposure_render.h"
#include "train/image_model.h"
#include "train/train_config.h"

namespace evflow {

class EdiWarmup {
 public:
  // Computes every training view's EDI targets (in cfg.loss_space) once, at each of
  // `frame_times` (the trajectory's virtual frames, 0.5 among them) with edi_warmup_motion,
  // else at 0.5. The caller has checked the settings (check_edi_warmup).
  EdiWarmup(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg, const std::vector<double>& frame_times);

  // Whether training step `step` (counted from 1) is a warm-up step.
  bool active(uint32_t step) const { return step <= last_step_; }

  // Records the mid-exposure render's image model; the render itself is submitted here.
  void forward(gpu::Commands& cmd, Rasterizer& raster, const GaussianBuffers& params, const Camera& camera,
               const RenderSettings& settings);
  const ImageModel& image_model() const { return *image_model_; }
  // Whether step `step` fits a virtual frame (edi_warmup_motion's share of the warm-up).
  bool motion(uint32_t step) const { return step <= motion_steps_; }
  // Which target step `step` fits for its view: in the virtual-frame steps each view's visits
  // cycle through the frames; else the mid-exposure one.
  uint32_t frame(uint32_t step, uint32_t view, size_t views) const;
  const gpu::Buffer& target(uint32_t view, uint32_t frame) const { return targets_.at(view * frames_ + frame); }
  // Records the render's gradient from the image terms' (then submitted by the caller).
  void render_grads(gpu::Commands& cmd);
  // Through the rasterizer into `grads`; returns the render's pose gradient (se(3)).
  lie::Vec6 backward(Rasterizer& raster, const GaussianBuffers& params, const gpu::Buffer& v_alpha,
                     GaussianBuffers& grads) const;

 private:
  uint32_t last_step_, motion_steps_;
  uint32_t frames_;                   // targets per view: 2N+1 or 1
  std::vector<gpu::Buffer> targets_;  // view-major
  ExposureRender render_;
  std::unique_ptr<ImageModel> image_model_;
};

// The settings edi_warmup needs (in range, blur mode, events; edi_warmup_motion only with a
// warm-up); throws naming the conflict.
void check_edi_warmup(const TrainConfig& cfg, const io::Dataset& data);

}  // namespace evflow
