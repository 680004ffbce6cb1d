// The event-residual loss L_res (engine/loss/residual_loss.h): its value and the gradient it adds
// into every frame against central differences of the formula in double precision; in training,
// the term's value in curve.csv and its gradients moving the model.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <random>

#include <unistd.h>

#include "camera/trajectory.h"
#include "cli_helpers.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "loss/residual_loss.h"
#include "nn/safetensors.h"
#include "plot/curve_plot.h"
#include "prior/residual_net.h"

using namespace evflow;

namespace {

std::vector<float> random_floats(size_t n, uint32_t seed, float scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-scale, scale);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// L = 1/F sum_i mean ((F_i - F_N) - R_i)^2, R_N = 0, in double.
double residual_loss(const std::vector<std::vector<double>>& frames, const std::vector<std::vector<double>>& prior) {
  const size_t F = frames.size(), mid = F / 2, n = frames[0].size();
  double sum = 0;
  for (size_t i = 0, k = 0; i < F; ++i) {
    if (i == mid) continue;
    for (size_t j = 0; j < n; ++j) {
      const double d = frames[i][j] - frames[mid][j] - prior[k][j];
      sum += d * d;
    }
    ++k;
  }
  return sum / (double(F) * double(n));
}

}  // namespace

TEST_CASE("residual loss: value and per-frame gradients against central differences", "[gpu][loss]") {
  auto& ctx = test::gpu_context();
  const uint32_t W = 7, H = 5, F = 5, n = W * H * 3;
  const float weight = 0.3f;
  ResidualLoss loss(ctx, W, H, F, 2, weight);
  std::vector<std::vector<double>> frames(F), prior(F - 1);
  std::vector<gpu::Buffer> rgb, grad;
  std::vector<std::vector<float>> grad0(F);
  std::vector<float> prior_planes;
  for (uint32_t i = 0; i < F; ++i) {
    const auto v = random_floats(n, 10 + i, 1.0f);
    frames[i].assign(v.begin(), v.end());
    rgb.emplace_back(ctx, n * 4, "rgb");
    rgb.back().write(v);
    grad0[i] = random_floats(n, 20 + i, 0.5f);  // the term adds to what is there
    grad.emplace_back(ctx, n * 4, "grad");
    grad.back().write(grad0[i]);
  }
  for (uint32_t k = 0; k + 1 < F; ++k) {
    const auto v = random_floats(n, 30 + k, 0.5f);
    prior[k].assign(v.begin(), v.end());
    prior_planes.insert(prior_planes.end(), v.begin(), v.end());
  }
  loss.set_view_residuals(1, prior_planes);
  ExposureFrames f;
  f.view = 1, f.width = W, f.height = H, f.t0 = 0, f.t1 = 1;
  f.u = ExposureTrajectory::virtual_times(int(F / 2));
  for (uint32_t i = 0; i < F; ++i) f.rgb.push_back(&rgb[i]), f.grad.push_back(&grad[i]);
  gpu::Commands cmd(ctx);
  loss.record(cmd, f);
  cmd.submit();
  CHECK(loss.value() == Approx(residual_loss(frames, prior)).epsilon(1e-5));
  const double h = 1e-3;
  for (uint32_t i = 0; i < F; ++i) {
    const auto g = grad[i].read<float>(n);
    for (uint32_t j = 0; j < n; ++j) {
      const double keep = frames[i][j];
      frames[i][j] = keep + h;
      const double up = residual_loss(frames, prior);
      frames[i][j] = keep - h;
      const double down = residual_loss(frames, prior);
      frames[i][j] = keep;
      const double want = weight * (up - down) / (2 * h);
      INFO("frame " << i << " element " << j);
      REQUIRE(double(g[j] - grad0[i][j]) == Approx(want).margin(1e-6).epsilon(1e-3));
    }
  }
  f.view = 0;  // no residuals set for view 0
  REQUIRE_THROWS_WITH(loss.record(cmd, f), Catch::Contains("no residuals for view 0"));
  REQUIRE_THROWS_WITH(loss.set_view_residuals(0, std::vector<float>(3)), Catch::Contains("expected"));
  test::require_no_validation_messages();
}

TEST_CASE("residual loss in training: a finite L_res, summed into the loss, whose gradients move the model",
          "[train][gpu][prior]") {
  namespace fs = std::filesystem;
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_residual_train");
  std::string out;
  REQUIRE(test::run_evflow(dir,
                           "simulate --scene objects --out sim --width 40 --height 30 --seed 3 --train-views 3 "
                           "--novel-views 1",
                           out) == 0);
  // A small prior with random weights (its output layer too, so that R is not zero).
  prior::ResidualNet net(test::gpu_context(), {7, 2}, 8, 8);
  net.init_he(11);
  nn::Conv2d& last = *net.layers().back();
  last.init_he(12);
  nn::save_safetensors(dir / "prior.safetensors", net.save());
  auto train = [&](const std::string& run, const std::string& keys) {
    const std::string a =
        "train sim --out " + run +
        " method=blur-only event_from=0 event_weight_end=1 iterations=6 init_gaussians=300 max_gaussians=600 "
        "sh_degree=0 res_prior=prior.safetensors " +
        keys;
    const int rc = test::run_evflow(dir, a, out);
    INFO(a << "\n" << out);
    REQUIRE(rc == 0);
    return plot::read_curve_csv(dir / run / "curve.csv");
  };
  // A large weight, so that L_res's share of the update shows in the logged digits.
  const plot::CurveTable with = train("res", "res_weight=10"), without = train("plain", "res_weight=0");
  const int res = with.column("residual"), image = with.column("l1_ssim"), loss = with.column("loss");
  REQUIRE(res >= 0);
  REQUIRE(with.rows.size() == 6);
  for (const auto& r : with.rows) {
    REQUIRE(std::isfinite(r[size_t(res)]));
    REQUIRE(r[size_t(res)] > 0.0);
    CHECK(r[size_t(loss)] == Approx(r[size_t(image)] + 10 * r[size_t(res)]).epsilon(1e-4));
  }
  // The first step renders the same model; by the last, L_res's gradients have moved it (one
  // Adam step of either is too small to show in the logged digits).
  CHECK(with.rows[0][size_t(image)] == without.rows[0][size_t(image)]);
  CHECK(with.rows[5][size_t(image)] != without.rows[5][size_t(image)]);
  CHECK(test::run_evflow(dir,
                         "train sim --out bad method=blur-only res_weight=0.1 virtual_frames=2 iterations=1 "
                         "res_prior=prior.safetensors",
                         out) != 0);
  CHECK(out.find("the residual prior predicts 7 virtual frames") != std::string::npos);
  CHECK(test::run_evflow(dir, "train sim --out bad2 method=blur-only res_weight=0.1 res_prior=none.safetensors", out) !=
        0);
  CHECK(out.find("none.safetensors") != std::string::npos);
  fs::remove_all(dir);
}
