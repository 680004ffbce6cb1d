// The EDI warm-up of a blur-mode run (edi_warmup > 0): for its first steps, each step fits one
// render, the view's trajectory at mid-exposure (u = 0.5), to the view's EDI image (the blurry
// input deblurred by EDI with the dataset's events and thresholds), as the 3DGS+EDI baseline
// does. A step of it costs one render instead of 2N+1, so the splats reach the scene's shape
// and colours for a fraction of the blur steps' time; the blur model and its terms then refine
// what EDI gets wrong. The mid-exposure pose gradient moves the trajectory as a whole.
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
  // Computes every training view's EDI target (in cfg.loss_space) once. The caller has checked
  // the settings (check_edi_warmup).
  EdiWarmup(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg);

  // Whether training step `step` (counted from 1) is a warm-up step.
  bool active(uint32_t step) const { return step <= last_step_; }

  // Records the mid-exposure render's image model; the render itself is submitted here.
  void forward(gpu::Commands& cmd, Rasterizer& raster, const GaussianBuffers& params, const Camera& camera,
               const RenderSettings& settings);
  const ImageModel& image_model() const { return *image_model_; }
  const gpu::Buffer& target(uint32_t view) const { return targets_.at(view); }
  // Records the render's gradient from the image terms' (then submitted by the caller).
  void render_grads(gpu::Commands& cmd);
  // Through the rasterizer into `grads`; returns the render's pose gradient (se(3)).
  lie::Vec6 backward(Rasterizer& raster, const GaussianBuffers& params, const gpu::Buffer& v_alpha,
                     GaussianBuffers& grads) const;

 private:
  uint32_t last_step_;
  std::vector<gpu::Buffer> targets_;
  ExposureRender render_;
  std::unique_ptr<ImageModel> image_model_;
};

// The settings edi_warmup needs (blur mode, events, no LDI branch); throws naming the conflict.
void check_edi_warmup(const TrainConfig& cfg, const io::Dataset& data);

}  // namespace evflow
