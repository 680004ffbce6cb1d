#include "train/edi_warmup.h"

#include <stdexcept>
#include <string>

#include "train/training_data.h"

namespace evflow {

void check_edi_warmup(const TrainConfig& cfg, const io::Dataset& data) {
  if (!(cfg.edi_warmup >= 0 && cfg.edi_warmup < 1))
    throw std::invalid_argument("edi_warmup must be in [0, 1), got " + std::to_string(cfg.edi_warmup));
  if (cfg.edi_warmup == 0) return;
  if (cfg.mode != TrainMode::Blur)
    throw std::invalid_argument(
        "edi_warmup > 0 needs mode=blur (plain mode fits one image per step already; "
        "target=edi is the EDI baseline)");
  if (data.events.size() == 0)
    throw std::invalid_argument("edi_warmup > 0 needs an event stream with times for EDI, and the dataset in '" +
                                data.root + "' has none");
}

static TrainConfig edi_target(TrainConfig cfg) {
  cfg.target = TrainTarget::Edi;
  return cfg;
}

EdiWarmup::EdiWarmup(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg)
    : last_step_(cfg.edi_warmup_steps()), render_(ctx, 1) {
  const TrainConfig edi = edi_target(cfg);
  for (size_t v = 0; v < data.train.size(); ++v) {
    const std::vector<float> planar = loss_space_target(data, v, edi);
    targets_.emplace_back(ctx, planar.size() * 4, "edi_target_" + data.train[v].name);
    targets_.back().write(planar);
  }
  const Camera& c0 = data.train.at(0).camera;
  image_model_ = std::make_unique<ImageModel>(ctx, 1, c0.width, c0.height, cfg.loss_space);
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
