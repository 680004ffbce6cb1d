// The image model of blur mode (engine/train/image_model.h) at sizes whose planes are not a whole
// number of vec4s: its kernels read their inputs as texels four floats at a time, so the last,
// partly used texel of every buffer must hold the last elements. The mean of the decoded frames
// (every frame in one pass, or decode and mean in one pass a frame) and the renders' gradients
// against the double reference.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <tuple>

#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "reference/srgb_reference.h"
#include "train/image_model.h"

using namespace evflow;

using reference::srgb_decode;
using reference::srgb_decode_deriv;

TEST_CASE(
    "image model: the blur mean and the renders' gradients match the double reference when H*W*3 is not a "
    "multiple of 4",
    "[train]") {
  auto& ctx = test::gpu_context();
  // 5 and 9 frames: one pass decodes them all (train/decode_mean_f<F>); 11: a pass per frame.
  for (const auto& [W, H, F] :
       {std::tuple<uint32_t, uint32_t, uint32_t>{7, 5, 5}, {9, 6, 5}, {3, 1, 5}, {7, 5, 9}, {7, 5, 11}, {3, 1, 11}}) {
    const uint32_t n = 3 * W * H;
    INFO(W << "x" << H << ", " << F << " frames: " << n << " values, " << n % 4 << " in the last vec4");
    std::mt19937 rng(W * 31 + H);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<std::vector<float>> renders(F, std::vector<float>(n));
    for (auto& r : renders)
      for (auto& v : r) v = u(rng);
    renders[1][n - 1] = 0.01f;  // the last element on the linear segment of the decode
    renders[2][0] = -0.2f;      // renders can leave [0, 1]: below 0 the linear segment continues,
    renders[3][n - 1] = 1.3f;   // above 1 the power segment
    ImageModel model(ctx, F, W, H, LossSpace::Linear, 1);
    std::vector<gpu::Buffer> rb;
    std::vector<const gpu::Buffer*> rp;
    for (auto& r : renders) rb.emplace_back(ctx, n * 4, "render"), rb.back().write(r);
    for (auto& b : rb) rp.push_back(&b);
    gpu::Commands cmd(ctx);
    model.forward(cmd, rp, nullptr);
    cmd.submit();

    const std::vector<float> mean = model.prediction().read<float>(n);
    for (uint32_t k = 0; k < n; ++k) {
      double want = 0;
      for (auto& r : renders) want += srgb_decode(r[k]) / F;
      INFO("element " << k);
      REQUIRE(std::abs(mean[k] - want) < 1e-6);
    }
    for (uint32_t i = 0; i < F; ++i) {
      const std::vector<float> lin = model.linear_frame(i).read<float>(n);
      for (uint32_t k = 0; k < n; ++k) REQUIRE(std::abs(lin[k] - srgb_decode(renders[i][k])) < 1e-6);
    }

    // L = sum_k c_k mean_k: d/d(render_i)_k = c_k decode'(render_ik) / F.
    std::vector<float> c(n);
    for (auto& v : c) v = u(rng) - 0.5f;
    std::vector<float> scaled = c;
    for (auto& v : scaled) v /= float(model.mean_count());
    const_cast<gpu::Buffer&>(model.prediction_grad()).write(scaled);
    model.render_grads(cmd, {});
    cmd.submit();
    for (uint32_t i = 0; i < F; ++i) {
      const std::vector<float> g = model.render_grad(i).read<float>(n);
      for (uint32_t k = 0; k < n; ++k) {
        const double want = c[k] * srgb_decode_deriv(renders[i][k]) / F;
        INFO("frame " << i << " element " << k << ": gpu " << g[k] << ", reference " << want);
        REQUIRE(std::abs(g[k] - want) < 1e-6 + 1e-5 * std::abs(want));
      }
    }
  }
  test::require_no_validation_messages();
}
