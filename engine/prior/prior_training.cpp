#include "prior/prior_training.h"

#include <chrono>
#include <memory>
#include <random>
#include <stdexcept>

#include "gpu/commands.h"

namespace evflow::prior {

namespace {

// d(loss)/d(output) of the mean squared error over a batch of `batch` crops, and the crop's error sum.
double squared_error_grad(const std::vector<float>& out, const std::vector<float>& target, double count,
                          std::vector<float>& grad) {
  double sum = 0;
  grad.resize(out.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const double e = double(out[i]) - target[i];
    sum += e * e;
    grad[i] = float(2.0 * e / count);
  }
  return sum;
}

}  // namespace

uint32_t train_prior(gpu::Context& ctx, ResidualNet& net, const std::vector<PriorSample>& samples,
                     const PriorTrainOptions& o, const std::function<void(const StepLog&)>& log) {
  if (samples.empty()) throw std::invalid_argument("train prior: no samples");
  if (net.height() != o.crop || net.width() != o.crop)
    throw std::invalid_argument("train prior: net is not crop-sized");
  for (const PriorSample& s : samples)
    if (s.width < o.crop || s.height < o.crop)
      throw std::invalid_argument("train prior: a sample is smaller than a crop");
  AdamOptions ao;
  ao.eps = 1e-8;
  Adam adam(ctx, ao);
  net.add_to(adam, o.lr);
  gpu::Commands cmd(ctx);
  std::mt19937_64 rng(o.seed);
  const auto start = std::chrono::steady_clock::now();
  const double count = double(net.output().count()) * o.batch;
  std::vector<float> grad;
  uint32_t step = 0;
  while (step < o.steps) {
    double sum = 0;
    for (uint32_t b = 0; b < o.batch; ++b) {
      const PriorSample& s = samples[std::uniform_int_distribution<size_t>(0, samples.size() - 1)(rng)];
      const uint32_t x = std::uniform_int_distribution<uint32_t>(0, s.width - o.crop)(rng);
      const uint32_t y = std::uniform_int_distribution<uint32_t>(0, s.height - o.crop)(rng);
      const Crop c = crop(s, x, y, o.crop);
      net.input().upload(c.input);
      net.forward(cmd);
      cmd.submit();
      sum += squared_error_grad(net.output().download(), c.target, count, grad);
      net.output_grad().upload(grad);
      net.backward(cmd, false, b > 0);
      cmd.submit();
    }
    adam.step(cmd);
    cmd.submit();
    ++step;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    log(StepLog{step, sum / count, seconds});
    if (o.max_seconds > 0 && seconds >= o.max_seconds) break;
  }
  return step;
}

ResidualErrors score_prior(gpu::Context& ctx, const ResidualNet& weights, const std::vector<PriorSample>& samples) {
  ResidualErrors e;
  std::unique_ptr<ResidualNet> net;
  gpu::Commands cmd(ctx);
  for (const PriorSample& s : samples) {
    if (!net || net->width() != s.width || net->height() != s.height) {
      net = std::make_unique<ResidualNet>(ctx, weights.spec(), s.height, s.width);
      net->copy_weights_from(weights);
    }
    net->input().upload(s.input);
    net->forward(cmd);
    cmd.submit();
    const std::vector<float> out = net->output().download();
    for (size_t i = 0; i < out.size(); ++i) {
      const double t = s.target[i];
      e.network += (out[i] - t) * (out[i] - t);
      e.zero += t * t;
      if (!s.edi_residual.empty()) e.edi += (s.edi_residual[i] - t) * (s.edi_residual[i] - t);
    }
    e.values += out.size();
  }
  if (e.values) e.network /= e.values, e.zero /= e.values, e.edi /= e.values;
  return e;
}

}  // namespace evflow::prior
