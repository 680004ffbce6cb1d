#include "loss/residual_loss.h"

#include <stdexcept>
#include <string>

#include "loss/loss_layout.h"

namespace evflow {

ResidualLoss::ResidualLoss(gpu::Context& ctx, uint32_t width, uint32_t height, uint32_t frames, uint32_t views,
                           float weight)
    : ExposureLossTerm(ctx, "residual", weight, 1),
      width_(width),
      height_(height),
      frames_(frames),
      residuals_(views),
      set_(views, false),
      partials_(ctx, 16, "residual_partials") {
  if (frames < 3 || frames % 2 == 0)
    throw std::invalid_argument("residual loss: needs an odd number (>= 3) of virtual frames, got " +
                                std::to_string(frames));
  const uint64_t n = uint64_t(width) * height * 3;
  const uint32_t groups = gpu::Commands::div_up(n, shaderio::kLossGroupSize);
  partials_.ensure(uint64_t(groups) * (frames - 1) * 16);
}

void ResidualLoss::set_view_residuals(uint32_t view, const std::vector<float>& residuals) {
  const size_t n = size_t(width_) * height_ * 3;
  if (view >= residuals_.size() || residuals.size() != n * (frames_ - 1))
    throw std::invalid_argument("residual loss: view " + std::to_string(view) + " gets " +
                                std::to_string(residuals.size()) + " values, expected " +
                                std::to_string(n * (frames_ - 1)));
  auto& bufs = residuals_[view];
  if (bufs.empty())
    for (uint32_t i = 0; i + 1 < frames_; ++i) bufs.emplace_back(ctx_, n * 4, "residual_prior");
  for (uint32_t i = 0; i + 1 < frames_; ++i)
    bufs[i].write(std::vector<float>(residuals.begin() + i * n, residuals.begin() + (i + 1) * n));
  set_[view] = true;
}

std::vector<float> ResidualLoss::view_residuals(uint32_t view) const {
  if (view >= set_.size() || !set_[view])
    throw std::logic_error("residual loss: no residuals for view " + std::to_string(view));
  const size_t n = size_t(width_) * height_ * 3;
  std::vector<float> out;
  for (const gpu::Buffer& b : residuals_[view]) {
    const std::vector<float> r = b.read<float>(n);
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}

void ResidualLoss::record(gpu::Commands& cmd, const ExposureFrames& f, float weight) {
  if (f.rgb.size() != frames_ || f.grad.size() != frames_ || f.width != width_ || f.height != height_)
    throw std::invalid_argument("residual loss: the exposure's frames do not match the term's size");
  if (f.view >= set_.size() || !set_[f.view])
    throw std::logic_error("residual loss: no residuals for view " + std::to_string(f.view));
  const uint64_t n = uint64_t(width_) * height_ * 3;
  const uint32_t groups = gpu::Commands::div_up(n, shaderio::kLossGroupSize), mid = frames_ / 2;
  shaderio::ResidualPC pc{};
  pc.count = uint32_t(n);
  pc.grad_scale = float(double(weight) / (double(frames_) * double(n)));
  for (uint32_t i = 0, k = 0; i < frames_; ++i) {
    if (i == mid) continue;
    pc.partial_base = k * groups;
    cmd.dispatch("loss/residual",
                 {{shaderio::kResidualBindFrame, *f.rgb[i]},
                  {shaderio::kResidualBindMid, *f.rgb[mid]},
                  {shaderio::kResidualBindPrior, residuals_[f.view][k]},
                  {shaderio::kResidualBindGradFrame, *f.grad[i]},
                  {shaderio::kResidualBindGradMid, *f.grad[mid]},
                  {shaderio::kResidualBindPartials, partials_}},
                 pc, cmd.linear_groups(groups));
    ++k;
  }
  shaderio::ReducePC r{};
  r.coeff0 = glm::vec4(float(1.0 / (double(frames_) * double(n))), 0, 0, 0);
  r.n_partials = groups * (frames_ - 1);
  r.dst = value_offset();
  r.n_out = 1;
  cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials_}, {shaderio::kReduceBindOut, value_buffer()}},
               r, gpu::Groups{1, 1, 1});
}

}  // namespace evflow
