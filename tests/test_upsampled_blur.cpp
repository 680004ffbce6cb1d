// The flow-upsampled blur (engine/train/image_model.h, paper Eq. 9): the mean of the 2NM+1
// frames and its gradients against the double reference with finite differences, the exposure
// terms' path equal to the plain one, and a blur that follows the motion better than 2N+1 frames.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "reference/srgb_reference.h"
#include "reference/upsample_reference.h"
#include "train/image_model.h"

using namespace evflow;

namespace {

// Random flow planes per interval: a smooth field, a block moving against it (a motion boundary),
// large displacements near the border, and a few zeroed pixels (where a flow was not finite).
std::vector<float> random_flow(uint32_t W, uint32_t H, uint32_t intervals, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> flow;
  for (uint32_t i = 0; i < intervals; ++i) {
    const float ax = 3 * u(rng), ay = 2 * u(rng), gx = 0.2f * u(rng), gy = 0.2f * u(rng);
    for (uint32_t c = 0; c < 2; ++c)
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
          float v = (c == 0 ? ax : ay) + (c == 0 ? gx : gy) * float(c == 0 ? x : y) + 0.3f * u(rng);
          if (x > W / 2 && x < W / 2 + 5 && y > 3 && y < 9) v = -v + 2.0f;  // the block
          if (x == W - 1) v *= 3.0f;
          if ((x * 7 + y * 3) % 23 == 0) v = 0.0f;
          flow.push_back(v);
        }
  }
  return flow;
}

struct Model {
  std::unique_ptr<ImageModel> model;
  std::vector<gpu::Buffer> renders;
  gpu::Buffer flow;
};

Model run_forward(uint32_t W, uint32_t H, const std::vector<std::vector<float>>& renders,
                  const std::vector<float>& flow, uint32_t M) {
  auto& ctx = test::gpu_context();
  Model m;
  m.model = std::make_unique<ImageModel>(ctx, uint32_t(renders.size()), W, H, LossSpace::Linear, M);
  for (auto& r : renders) {
    m.renders.emplace_back(ctx, r.size() * 4, "render");
    m.renders.back().write(r);
  }
  m.flow = gpu::Buffer(ctx, flow.size() * 4, "flow");
  m.flow.write(flow);
  std::vector<const gpu::Buffer*> rp;
  for (auto& b : m.renders) rp.push_back(&b);
  gpu::Commands cmd(ctx);
  m.model->forward(cmd, rp, &m.flow);
  cmd.submit();
  return m;
}

}  // namespace

TEST_CASE("upsampled blur: the mean of 2NM+1 frames and its gradients match the double reference",
          "[train][upsample]") {
  const uint32_t W = 22, H = 14, F = 5, M = 4;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.05f, 0.95f);
  std::vector<std::vector<float>> renders(F, std::vector<float>(3 * W * H));
  for (auto& r : renders)
    for (auto& v : r) v = u(rng);
  const std::vector<float> flow = random_flow(W, H, F - 1, 9);
  Model m = run_forward(W, H, renders, flow, M);
  REQUIRE(m.model->mean_count() == 17);

  std::vector<std::vector<double>> linear;
  for (auto& r : renders) {
    linear.emplace_back();
    for (float v : r) linear.back().push_back(reference::srgb_decode(v));
  }
  const std::vector<double> want = reference::upsampled_mean(linear, flow, W, H, M);
  const std::vector<float> got = m.model->prediction().read<float>(3 * W * H);
  double worst = 0;
  for (size_t k = 0; k < want.size(); ++k) worst = std::max(worst, std::abs(double(got[k]) - want[k]));
  INFO("largest difference from the reference mean " << worst);
  REQUIRE(worst < 2e-6);

  // L = sum_k c_k mean_k: the image terms would write c / mean_count into prediction_grad.
  std::vector<float> c(3 * W * H);
  for (auto& v : c) v = u(rng) - 0.5f;
  std::vector<float> scaled = c;
  for (auto& v : scaled) v /= float(m.model->mean_count());
  const_cast<gpu::Buffer&>(m.model->prediction_grad()).write(scaled);
  auto& ctx = test::gpu_context();
  gpu::Commands cmd(ctx);
  m.model->render_grads(cmd, {});
  cmd.submit();
  int bad = 0, checked = 0;
  for (uint32_t i = 0; i < F; ++i) {
    const std::vector<float> g = m.model->render_grad(i).read<float>(3 * W * H);
    for (size_t k = i; k < g.size(); k += 7) {
      const double h = 1e-6, x0 = renders[i][k];
      auto loss = [&](double x) {
        linear[i][k] = reference::srgb_decode(x);
        const std::vector<double> mean = reference::upsampled_mean(linear, flow, W, H, M);
        double l = 0;
        for (size_t e = 0; e < mean.size(); ++e) l += c[e] * mean[e];
        return l;
      };
      const double fd = (loss(x0 + h) - loss(x0 - h)) / (2 * h);
      linear[i][k] = reference::srgb_decode(x0);
      ++checked;
      if (std::abs(g[k] - fd) > 1e-3 * std::abs(fd) + 1e-6) {
        ++bad;
        UNSCOPED_INFO("frame " << i << " element " << k << ": gpu " << g[k] << " fd " << fd);
      }
    }
  }
  CHECK(checked > 600);
  REQUIRE(bad == 0);

  // The exposure terms' path (each frame's share into a caller's buffer) gives the same gradients.
  std::vector<gpu::Buffer> shares;
  std::vector<const gpu::Buffer*> sp;
  for (uint32_t i = 0; i < F; ++i) shares.emplace_back(ctx, 3 * W * H * 4, "share");
  const auto before = m.model->render_grad(2).read<float>(3 * W * H);
  m.model->mean_grad(cmd);
  for (uint32_t i = 0; i < F; ++i) m.model->frame_share(cmd, i, shares[i]), sp.push_back(&shares[i]);
  m.model->render_grads(cmd, sp);
  cmd.submit();
  CHECK(m.model->render_grad(2).read<float>(3 * W * H) == before);
  test::require_no_validation_messages();
}

TEST_CASE("upsampled blur: with the true flow, 2NM+1 frames blur a fast pattern as the continuous motion does",
          "[train][upsample]") {
  // Stripes of period 10 px moving 12 px over the exposure: 3 frames alone leave ghost copies
  // 6 px apart; with M = 4 the mean follows the motion every 1.5 px.
  const uint32_t W = 64, H = 4, F = 3;
  auto stripes = [](double x) { return 0.45 + 0.4 * std::sin(2 * M_PI * x / 10.0); };
  auto frame_at = [&](double t) {
    std::vector<float> f(3 * W * H);
    for (uint32_t c = 0; c < 3; ++c)
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) f[(c * H + y) * W + x] = float(stripes(x - 12.0 * t));
    return f;
  };
  std::vector<double> truth(3 * W * H, 0.0);  // linear: the renders below hold linear-valued colours via decode
  const int steps = 240;
  for (int k = 0; k <= steps; ++k) {
    const auto f = frame_at(double(k) / steps);
    for (size_t e = 0; e < truth.size(); ++e) truth[e] += reference::srgb_decode(f[e]) / (steps + 1);
  }
  std::vector<std::vector<float>> renders;
  for (uint32_t i = 0; i < F; ++i) renders.push_back(frame_at(i / 2.0));
  std::vector<float> flow;
  for (uint32_t i = 0; i + 1 < F; ++i)
    for (uint32_t c = 0; c < 2; ++c)
      for (uint32_t p = 0; p < W * H; ++p) flow.push_back(c == 0 ? 6.0f : 0.0f);
  auto error = [&](uint32_t M) {
    Model m = run_forward(W, H, renders, flow, M);
    const auto got = m.model->prediction().read<float>(3 * W * H);
    double e = 0;
    size_t n = 0;
    for (uint32_t c = 0; c < 3; ++c)
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 16; x < W; ++x, ++n) {  // away from the left edge the motion uncovers
          const size_t k = (c * H + y) * W + x;
          e += (got[k] - truth[k]) * (got[k] - truth[k]);
        }
    return std::sqrt(e / double(n));
  };
  const double plain = error(1), upsampled = error(4);
  INFO("RMS error against the continuous blur: 3 frames " << plain << ", M = 4 " << upsampled);
  CHECK(upsampled < 0.6 * plain);
  test::require_no_validation_messages();
}
