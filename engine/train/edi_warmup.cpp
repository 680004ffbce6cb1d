#include "train/edi_warmup.h"

#include <stdexcept>
#include <string>

#include "train/training_data.h"

namespace evflow {

void check_edi_warmup(const TrainConfig& cfg, const io::Dataset& data) {
  require_fraction("edi_warmup", cfg.edi_warmup, false);
  require_fraction("edi_warmup_motion", cfg.edi_warmup_motion);
  if (cfg.edi_warmup == 0 && cfg.edi_warmup_motion > 0)
    throw std::invalid_argument("edi_warmup_motion > 0 is a share of the EDI warm-up: it needs edi_warmup > 0");
  if (cfg.edi_warmup == 0 && cfg.edi_keep_mid)
    throw std::invalid_argument("edi_keep_mid keeps the mid pose the EDI warm-up fitted: it needs edi_warmup > 0");
  if (cfg.edi_mid_lr > 0 && !cfg.edi_keep_mid)
    throw std::invalid_argument(
        "edi_mid_lr > 0 is the rate of the mid pose that edi_keep_mid keeps: it needs edi_keep_mid=true (without "
        "it the knots move the mid pose themselves)");
  if (cfg.edi_warmup == 0) return;
  if (cfg.mode != TrainMode::Blur)
    throw std::invalid_argument(
        "edi_warmup > 0 needs mode=blur (plain mode fits one image per step already; "
        "target=edi is the EDI baseline)");
  if (data.events.size() == 0)
    throw std::invalid_argument("edi_warmup > 0 needs an event stream with times for EDI, and the dataset in '" +
                                data.root + "' has none");
}

EdiWarmup::EdiWarmup(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg,
                     const std::vector<double>& frame_times)
    : last_step_(cfg.edi_warmup_steps()),
      motion_steps_(cfg.edi_motion_steps()),
      frames_(motion_steps_ > 0 ? uint32_t(frame_times.size()) : 1),
      render_(ctx, 1) {
  const std::vector<double> times = frames_ > 1 ? frame_times : std::vector<double>{0.5};
  for (size_t v = 0; v < data.train.size(); ++v)
    for (const io::Image& frame : edi_frames(data, v, cfg, times)) {
      const std::vector<float> planar = loss_space_image(frame, cfg);
      targets_.emplace_back(ctx, planar.size() * 4, "edi_target_" + data.train[v].name);
      targets_.back().write(planar);
    }
  const Camera& c0 = data.train.at(0).camera;
  image_model_ = std::make_unique<ImageModel>(ctx, 1, c0.width, c0.height, cfg.loss_space);
}

// view_for_step visits every view once per round of `views` steps; in the virtual-frame steps
// round r fits frame (r + view) mod frames, so the views' frames are spread over each round.
// The virtual frames' times are symmetric about 0.5: frame frames/2 is mid-exposure.
uint32_t EdiWarmup::frame(uint32_t step, uint32_t view, size_t views) const {
  return motion(step) ? uint32_t(((step - 1) / views + view) % frames_) : frames_ / 2;
}

void EdiWarmup::forward(gpu::Commands& cmd, Rasterizer& raster, const GaussianBuffers& params, const Camera& camera,
                        const RenderSettings& settings) {
  render_.forward(raster, params, {camera}, settings);
  image_model_->forward(cmd, render_.images());
}

void EdiWarmup::render_grads(gpu::Commands& cmd) { image_model_->render_grads(cmd, {}); }

lie::Vec6 EdiWarmup::backward(Rasterizer& raster, const GaussianBuffers& params, const gpu::Buffer& v_alpha,
                              GaussianBuffers& grads) const {
  return render_.backward(raster, params, {&image_model_->render_grad(0)}, v_alpha, grads).at(0);
}

}  // namespace evflow
