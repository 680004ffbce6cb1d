#include "loss/image_losses.h"

#include <stdexcept>
#include <string>

#include "loss/loss_layout.h"

namespace evflow {

using shaderio::kLossGroupSize;

namespace {

void check_image(const gpu::Buffer& b, const ImageShape& s, const std::string& what) {
  if (s.count() == 0) throw std::invalid_argument(what + ": empty image shape");
  if (s.count() > 0xFFFFFFFFull / 5) throw std::invalid_argument(what + ": image too large");
  if (b.size() < s.count() * 4)
    throw std::invalid_argument(what + ": buffer " + b.name() + " holds " + std::to_string(b.size()) +
                                " bytes, needs " + std::to_string(s.count() * 4));
}

uint32_t groups_for(const ImageShape& s) { return gpu::Commands::div_up(s.count(), kLossGroupSize); }

// One reduction of vec4 partials into affine outputs.
void record_reduce(gpu::Commands& cmd, const gpu::Buffer& partials, uint32_t n_partials,
                   const SsimPipeline::Outputs& o) {
  if (o.count == 0 || o.count > shaderio::kReduceMaxOutputs) throw std::invalid_argument("loss reduce: 1..4 outputs");
  if (o.values->size() < (uint64_t(o.first) + o.count) * 4)
    throw std::invalid_argument("loss reduce: value slot out of range");
  shaderio::ReducePC pc{};
  glm::vec4* coeff[4] = {&pc.coeff0, &pc.coeff1, &pc.coeff2, &pc.coeff3};
  for (uint32_t j = 0; j < 4; ++j) {
    *coeff[j] = glm::vec4(o.coeff[j][0], o.coeff[j][1], 0.0f, 0.0f);
    pc.offset[j] = o.offset[j];
  }
  pc.n_partials = n_partials;
  pc.dst = o.first;
  pc.n_out = o.count;
  pc.log_mask = o.log_mask;
  cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials}, {shaderio::kReduceBindOut, *o.values}}, pc,
               gpu::Groups{1, 1, 1});
}

}  // namespace

// ---------------------------------------------------------------------------------------------
SsimPipeline::SsimPipeline(gpu::Context& ctx)
    : ctx_(ctx), h_(ctx, 16, "ssim_h"), d_(ctx, 16, "ssim_d"), partials_(ctx, 16, "ssim_partials") {}

void SsimPipeline::record(gpu::Commands& cmd, const ImageShape& shape, const gpu::Buffer& a, const gpu::Buffer& b,
                          const gpu::Buffer* grad, float ssim_grad_scale, float pixel_grad_scale, bool accumulate,
                          bool pixel_l2, const Outputs& out, bool write_map) {
  check_image(a, shape, "ssim pred");
  check_image(b, shape, "ssim target");
  if (grad) check_image(*grad, shape, "ssim grad");
  const uint64_t n = shape.count();
  // One invocation per strip of kSsimStrip pixels: row segments (horizontal passes), column
  // strips (vertical passes).
  const uint64_t segs = gpu::Commands::div_up(shape.width, shaderio::kSsimStrip);
  const uint64_t strips = gpu::Commands::div_up(shape.height, shaderio::kSsimStrip);
  const uint32_t h_groups = gpu::Commands::div_up(uint64_t(shape.channels) * shape.height * segs, kLossGroupSize);
  const uint32_t v_groups = gpu::Commands::div_up(uint64_t(shape.channels) * strips * shape.width, kLossGroupSize);
  h_.ensure(4 * n * 4);  // a vec4 a pixel (loss_layout.h)
  d_.ensure(5 * n * 4);  // a vec4 a pixel, then the SSIM map
  partials_.ensure(uint64_t(v_groups) * 16);
  ctx_.check_binding_size(5 * n * 4, "ssim scratch");

  shaderio::SsimPC pc{};
  pc.channels = shape.channels;
  pc.height = shape.height;
  pc.width = shape.width;
  pc.count = static_cast<uint32_t>(n);
  pc.flags = (grad ? shaderio::kLossWriteGrad : 0u) | (accumulate ? shaderio::kLossAccumulate : 0u) |
             (pixel_l2 ? shaderio::kLossPixelL2 : 0u) | (write_map ? shaderio::kLossWriteSsimMap : 0u);
  pc.c1 = kSsimC1;
  pc.c2 = kSsimC2;
  pc.ssim_grad_scale = ssim_grad_scale;
  pc.pixel_grad_scale = pixel_grad_scale;
  const gpu::Groups g = cmd.linear_groups(h_groups), gv = cmd.linear_groups(v_groups);
  cmd.dispatch("loss/ssim_h", {{shaderio::kSsimHBindA, a}, {shaderio::kSsimHBindB, b}, {shaderio::kSsimHBindH, h_}}, pc,
               g);
  cmd.dispatch("loss/ssim_v",
               {{shaderio::kSsimVBindA, a},
                {shaderio::kSsimVBindB, b},
                {shaderio::kSsimVBindH, h_},
                {shaderio::kSsimVBindD, d_},
                {shaderio::kSsimVBindPartials, partials_}},
               pc, gv);
  record_reduce(cmd, partials_, v_groups, out);
  if (grad) {
    cmd.dispatch("loss/ssim_bwd_h", {{shaderio::kSsimBwdHBindD, d_}, {shaderio::kSsimBwdHBindH, h_}}, pc, g);
    cmd.dispatch("loss/ssim_bwd_v",
                 {{shaderio::kSsimBwdVBindA, a},
                  {shaderio::kSsimBwdVBindB, b},
                  {shaderio::kSsimBwdVBindH, h_},
                  {shaderio::kSsimBwdVBindGrad, *grad},
                  {shaderio::kSsimBwdVBindGradIn, *grad}},
                 pc, gv);
  }
}

// ---------------------------------------------------------------------------------------------
L1Loss::L1Loss(gpu::Context& ctx, ImageShape shape, float weight)
    : ImageLossTerm(ctx, "l1", weight, 1), shape_(shape), partials_(ctx, 16, "l1_partials") {}

void L1Loss::record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, const gpu::Buffer& grad_out,
                    float weight, bool accumulate) {
  check_image(pred, shape_, "l1 pred");
  check_image(target, shape_, "l1 target");
  check_image(grad_out, shape_, "l1 grad");
  const uint64_t n = shape_.count();
  const uint32_t groups = groups_for(shape_);
  partials_.ensure(uint64_t(groups) * 16);
  shaderio::PixelPC pc{};
  pc.count = static_cast<uint32_t>(n);
  pc.flags = shaderio::kLossWriteGrad | (accumulate ? shaderio::kLossAccumulate : 0u);
  pc.grad_scale = static_cast<float>(double(weight) / double(n));
  cmd.dispatch("loss/pixel",
               {{shaderio::kPixelLossBindA, pred},
                {shaderio::kPixelLossBindB, target},
                {shaderio::kPixelLossBindGrad, grad_out},
                {shaderio::kPixelLossBindPartials, partials_}},
               pc, cmd.linear_groups(groups));
  SsimPipeline::Outputs o;
  o.values = &value_buffer();
  o.first = value_offset();
  o.count = 1;
  o.coeff[0][0] = static_cast<float>(1.0 / double(n));
  record_reduce(cmd, partials_, groups, o);
}

// ---------------------------------------------------------------------------------------------
SsimLoss::SsimLoss(gpu::Context& ctx, ImageShape shape, float weight)
    : ImageLossTerm(ctx, "ssim", weight, 2), shape_(shape), pipe_(ctx) {}

void SsimLoss::record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target,
                      const gpu::Buffer& grad_out, float weight, bool accumulate) {
  const double inv_n = 1.0 / double(shape_.count());
  SsimPipeline::Outputs o;
  o.values = &value_buffer();
  o.first = value_offset();
  o.count = 2;
  o.coeff[0][1] = static_cast<float>(-inv_n);  // 1 - SSIM
  o.offset[0] = 1.0f;
  o.coeff[1][1] = static_cast<float>(inv_n);  // SSIM
  pipe_.record(cmd, shape_, pred, target, &grad_out, static_cast<float>(-double(weight) * inv_n), 0.0f, accumulate,
               false, o);
}

// ---------------------------------------------------------------------------------------------
BlendLoss::BlendLoss(gpu::Context& ctx, ImageShape shape, float lambda, float weight)
    : ImageLossTerm(ctx, "l1_ssim", weight, 3), shape_(shape), lambda_(lambda), pipe_(ctx) {}

void BlendLoss::record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target,
                       const gpu::Buffer& grad_out, float weight, bool accumulate) {
  const double inv_n = 1.0 / double(shape_.count());
  const double lam = lambda_;
  SsimPipeline::Outputs o;
  o.values = &value_buffer();
  o.first = value_offset();
  o.count = 3;
  o.coeff[0][0] = static_cast<float>((1.0 - lam) * inv_n);  // (1-l) L1 + l (1 - SSIM)
  o.coeff[0][1] = static_cast<float>(-lam * inv_n);
  o.offset[0] = static_cast<float>(lam);
  o.coeff[1][0] = static_cast<float>(inv_n);  // L1
  o.coeff[2][1] = static_cast<float>(inv_n);  // SSIM
  pipe_.record(cmd, shape_, pred, target, &grad_out, static_cast<float>(-double(weight) * lam * inv_n),
               static_cast<float>(double(weight) * (1.0 - lam) * inv_n), accumulate, false, o);
}

// ---------------------------------------------------------------------------------------------
ImageMetrics::ImageMetrics(gpu::Context& ctx, ImageShape shape)
    : shape_(shape), pipe_(ctx), values_(ctx, 16, "image_metrics") {}

void ImageMetrics::record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, bool write_map) {
  const double inv_n = 1.0 / double(shape_.count());
  SsimPipeline::Outputs o;
  o.values = &values_;
  o.first = 0;
  o.count = 3;
  o.coeff[0][0] = static_cast<float>(inv_n);  // PSNR = -10 log10(MSE)
  o.log_mask = 1u;
  o.coeff[1][1] = static_cast<float>(inv_n);  // SSIM
  o.coeff[2][0] = static_cast<float>(inv_n);  // MSE
  pipe_.record(cmd, shape_, pred, target, nullptr, 0.0f, 0.0f, false, true, o, write_map);
}

ImageMetrics::Values ImageMetrics::read() const {
  auto v = values_.read<float>(3);
  return {v[0], v[1], v[2]};
}

}  // namespace evflow
