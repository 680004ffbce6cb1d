// The trainer on sharp multi-view data rendered from random ground-truth Gaussians.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "gpu_fixture.h"
#include "loss/image_losses.h"
#include "splat/synthetic.h"
#include "train/checkpoint.h"
#include "camera/trajectory.h"
#include "train/synthetic_dataset.h"
#include "metrics/srgb_metrics.h"
#include "train/trainer.h"

using namespace evflow;

namespace {

io::Dataset make_dataset(gpu::Context& ctx, uint32_t w, uint32_t h, int n_train, int n_novel) {
  return render_synthetic_dataset(ctx, w, h, n_train, n_novel);
}

double mean_psnr(gpu::Context& ctx, Trainer& t, const std::vector<io::View>& views) {
  double sum = 0;
  for (auto& v : views) {
    // As `evflow eval` scores: the sRGB render against the linear ground truth, both as 8-bit sRGB.
    const uint32_t w = v.camera.width, h = v.camera.height;
    sum += metrics::psnr(metrics::quantise_srgb(t.render(v.camera), w, h, 3),
                         metrics::encode_linear(io::planar_rgb(*v.sharp_mid), w, h, 3));
  }
  return sum / views.size();
}

}  // namespace

TEST_CASE("trainer: fits held-out views of a scene of random Gaussians", "[gpu][train]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = make_dataset(ctx, 200, 150, 12, 4);
  TrainConfig cfg;
  // 3000 steps with density control from step 200 (about 3 min on 2 cores with lavapipe).
  cfg.iterations = 3000;
  cfg.init_gaussians = 3000;
  cfg.sh_degree = 0;
  cfg.target = "sharp";
  cfg.densify_from = 200;
  cfg.densify_every = 100;
  cfg.densify_until = 1500;
  Trainer t(ctx, data, cfg);
  const double before = mean_psnr(ctx, t, data.novel);
  auto t0 = std::chrono::steady_clock::now();
  double first_loss = 0, last_loss = 0;
  while (t.current_step() < cfg.iterations) {
    auto st = t.step();
    REQUIRE_FALSE(st.skipped);
    if (st.step <= 12) first_loss += st.loss;
    if (st.step > cfg.iterations - 12) last_loss += st.loss;
  }
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double after = mean_psnr(ctx, t, data.novel);
  std::printf("trainer: held-out PSNR %.2f dB -> %.2f dB after %u steps at 200x150 (%.1f it/s); loss %.4f -> %.4f\n", before,
              after, cfg.iterations, cfg.iterations / secs, first_loss / 12, last_loss / 12);
  REQUIRE(last_loss < 0.5 * first_loss);
  REQUIRE(after > before + 6.0);
  REQUIRE(after >= 30.0);  // held-out PSNR >= 30 dB at 200x150 within the test budget
  test::require_no_validation_messages();
}

TEST_CASE("trainer: a fixed seed gives the same run twice, and resuming is bit-identical", "[gpu][train]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = make_dataset(ctx, 96, 72, 4, 1);
  TrainConfig cfg;
  cfg.init_gaussians = 800;
  cfg.sh_degree = 1;
  cfg.sh_increase_every = 6;
  cfg.iterations = 16;
  cfg.seed = 5;
  auto run = [&](uint32_t steps) {
    Trainer t(ctx, data, cfg);
    while (t.current_step() < steps) t.step();
    return t.checkpoint();
  };
  Checkpoint a = run(16), b = run(16);
  REQUIRE(a.cloud.means == b.cloud.means);
  REQUIRE(a.cloud.sh == b.cloud.sh);
  REQUIRE(a.cloud.opacity_logits == b.cloud.opacity_logits);
  // 8 steps, through a checkpoint file, then 8 more.
  auto path = std::filesystem::temp_directory_path() / "evf_resume_test.ckpt";
  write_checkpoint(path, run(8));
  Trainer resumed(ctx, data, cfg, read_checkpoint(path));
  REQUIRE(resumed.current_step() == 8);
  while (resumed.current_step() < 16) resumed.step();
  Checkpoint c = resumed.checkpoint();
  REQUIRE(c.cloud.means == a.cloud.means);
  REQUIRE(c.cloud.log_scales == a.cloud.log_scales);
  REQUIRE(c.cloud.quats == a.cloud.quats);
  REQUIRE(c.cloud.sh == a.cloud.sh);
  for (size_t i = 0; i < a.optimizer.size(); ++i) {
    REQUIRE(c.optimizer[i].step == a.optimizer[i].step);
    REQUIRE(c.optimizer[i].exp_avg == a.optimizer[i].exp_avg);
  }
  std::filesystem::remove(path);
  test::require_no_validation_messages();
}

TEST_CASE("trainer: density control grows and prunes during training, state stays consistent", "[gpu][train]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = make_dataset(ctx, 128, 96, 6, 2);
  TrainConfig cfg;
  cfg.init_gaussians = 1500;
  cfg.sh_degree = 1;
  cfg.target = "sharp";
  cfg.iterations = 120;
  cfg.densify_from = 30;
  cfg.densify_every = 30;
  cfg.densify_grad_threshold = 5e-5;
  cfg.max_gaussians = 2500;
  Trainer t(ctx, data, cfg);
  std::vector<size_t> counts;
  while (t.current_step() < cfg.iterations) {
    auto st = t.step();
    REQUIRE_FALSE(st.skipped);
    if (st.step % 30 == 0) counts.push_back(t.params().count);
  }
  std::printf("density control in training: Gaussian count at steps 30/60/90/120: %zu %zu %zu %zu\n", counts[0], counts[1],
              counts[2], counts[3]);
  REQUIRE(counts.back() != 1500);
  for (size_t c : counts) REQUIRE(c <= 2500);
  Checkpoint c = t.checkpoint();
  REQUIRE(c.cloud.size() == t.params().count);
  for (auto& g : c.optimizer) REQUIRE(g.exp_avg.size() % c.cloud.size() == 0);
  test::require_no_validation_messages();
}

TEST_CASE("trainer: checkpoints round-trip and reject damaged files", "[train]") {
  Checkpoint c;
  c.step = 77;
  c.cloud = synthetic_cloud(3, 50, 2, Camera::look_at(64, 48, 60.0, {0, 0, 0}, {0, 0, 1}, {0, -1, 0}));
  auto dir = std::filesystem::temp_directory_path() / "evf_ckpt_test";
  std::filesystem::create_directories(dir);
  write_checkpoint(dir / "a.ckpt", c);
  Checkpoint r = read_checkpoint(dir / "a.ckpt");
  REQUIRE(r.step == 77);
  REQUIRE(r.cloud.means == c.cloud.means);
  REQUIRE(r.cloud.sh == c.cloud.sh);
  c.optimizer.push_back({"means", 12, std::vector<float>(150, 0.5f), std::vector<float>(150, 0.25f)});
  write_checkpoint(dir / "a.ckpt", c);
  r = read_checkpoint(dir / "a.ckpt");
  REQUIRE(r.optimizer.size() == 1);
  REQUIRE(r.optimizer[0].name == "means");
  REQUIRE(r.optimizer[0].step == 12);
  REQUIRE(r.optimizer[0].exp_avg_sq == c.optimizer[0].exp_avg_sq);
  std::filesystem::resize_file(dir / "a.ckpt", std::filesystem::file_size(dir / "a.ckpt") - 7);
  REQUIRE_THROWS_WITH(read_checkpoint(dir / "a.ckpt"), Catch::Contains("a.ckpt") && Catch::Contains("truncated"));
  REQUIRE_THROWS_WITH(read_checkpoint(dir / "missing.ckpt"), Catch::Contains("missing.ckpt"));
  // A cloud with a NaN is refused and the existing file is kept whole.
  write_checkpoint(dir / "b.ckpt", c);
  auto size = std::filesystem::file_size(dir / "b.ckpt");
  Checkpoint bad = c;
  bad.cloud.means[4] = std::nanf("");
  REQUIRE_THROWS(write_checkpoint(dir / "b.ckpt", bad));
  REQUIRE(std::filesystem::file_size(dir / "b.ckpt") == size);
  REQUIRE(read_checkpoint(dir / "b.ckpt").step == 77);
  std::filesystem::remove_all(dir);
}

TEST_CASE("trainer: config keys, presets and bad values", "[train]") {
  TrainConfig c;
  c.set("iterations", "123");
  c.set("background", "1,0.5,0");
  REQUIRE(c.iterations == 123);
  REQUIRE(c.background[1] == 0.5f);
  REQUIRE_THROWS_WITH(c.set("iterationz", "1"), Catch::Contains("iterationz"));
  REQUIRE_THROWS_WITH(c.set("iterations", "ten"), Catch::Contains("iterations"));
  REQUIRE(TrainConfig::preset_named("paper").iterations == 40000);
  // The trajectory's learning rate follows the preset's length.
  REQUIRE(TrainConfig::preset_named("paper").lr_trajectory_init == 1e-3);
  REQUIRE(TrainConfig::preset_named("fast").lr_trajectory_init == 6e-3);
  REQUIRE(TrainConfig::preset_named("fast").lr_trajectory_final == 6e-4);
  c.set("prune_screen_px", "20");
  c.set("prune_world_scale", "0");
  REQUIRE(c.prune_screen_px == 20.0);
  REQUIRE(c.prune_world_scale == 0.0);
  REQUIRE(TrainConfig{}.prune_screen_px == 0.0);  // the size rules are off by default
  REQUIRE(TrainConfig{}.prune_world_scale == 0.0);
  TrainConfig d;
  d.apply_json(c.to_json());
  REQUIRE(d.to_json() == c.to_json());
}

TEST_CASE("blur mode: mid-exposure render of a zero-motion trajectory equals the plain render", "[gpu][train][camera]") {
  auto& ctx = test::gpu_context();
  Camera cam = Camera::look_at(80, 60, 60.0, {0.3, -0.2, 0}, {0, 0, 6}, {0, -1, 0});
  GaussianCloud cloud = synthetic_cloud(9, 500, 1, cam);
  GaussianBuffers p(ctx, cloud.size(), 1, "p_");
  p.upload(cloud);
  Rasterizer r(ctx);
  r.forward(p, cam, RenderSettings{});
  auto plain = r.outputs().rgb.read<float>(80 * 60 * 3);
  ExposureTrajectory still(cam, 0, 0.0);
  r.forward(p, still.camera_at(0.5), RenderSettings{});
  auto mid = r.outputs().rgb.read<float>(80 * 60 * 3);
  REQUIRE(mid == plain);
  test::require_no_validation_messages();
}

TEST_CASE("blur mode: the mean of virtual renders is fitted, knots learn, trajectories checkpoint", "[gpu][train]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = make_dataset(ctx, 96, 72, 4, 1);
  // Blur the training images with a known exposure motion: the mean of 7 renders along it.
  {
    Camera c0 = Camera::look_at(96, 72, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
    GaussianCloud truth = synthetic_cloud(42, 1500, 0, c0);
    GaussianBuffers gt(ctx, truth.size(), 0, "gt_");
    gt.upload(truth);
    Rasterizer r(ctx);
    for (size_t v = 0; v < data.train.size(); ++v) {
      ExposureTrajectory motion(data.train[v].camera, 100 + v, 0.0);
      for (int j = 0; j < ExposureTrajectory::kKnots; ++j) {
        motion.data()[j * 6 + 0] = 0.04 * (j - 4) / 4.0;   // sideways drift across the exposure
        motion.data()[j * 6 + 4] = 0.01 * (j - 4) / 4.0;   // and a little yaw
      }
      std::vector<float> mean(96 * 72 * 3, 0.f);
      for (double u : ExposureTrajectory::virtual_times(3)) {
        r.forward(gt, motion.camera_at(u), RenderSettings{});
        auto img = r.outputs().rgb.read<float>(mean.size());  // sRGB values: the blur averages linear light
        for (size_t i = 0; i < mean.size(); ++i) mean[i] += io::srgb_to_linear(img[i]) / 7.0f;
      }
      data.train[v].blurry = io::image_from_planar_rgb(mean, 96, 72);
    }
  }
  TrainConfig cfg;
  cfg.mode = "blur";
  cfg.init_gaussians = 1500;
  cfg.sh_degree = 0;
  cfg.iterations = 40;
  cfg.densify = false;
  Trainer t(ctx, data, cfg);
  REQUIRE(t.trajectories().size() == 4);
  double first = 0, last = 0;
  while (t.current_step() < cfg.iterations) {
    auto st = t.step();
    REQUIRE_FALSE(st.skipped);
    if (st.step <= 4) first += st.loss;
    if (st.step > cfg.iterations - 4) last += st.loss;
  }
  REQUIRE(last < 0.8 * first);
  double moved = 0;
  for (auto& tr : t.trajectories())
    for (size_t k = 0; k < ExposureTrajectory::kSize; ++k) moved = std::max(moved, std::abs(tr.data()[k]));
  std::printf("blur mode: loss %.4f -> %.4f over %u steps, largest knot component %.3g\n", first / 4, last / 4,
              cfg.iterations, moved);
  REQUIRE(moved > 1e-3);  // the knots learned (they start at ~1e-5)
  auto path = std::filesystem::temp_directory_path() / "evf_blur.ckpt";
  write_checkpoint(path, t.checkpoint());
  Checkpoint c = read_checkpoint(path);
  REQUIRE(c.trajectories.size() == 4);
  REQUIRE(c.trajectories[2].knots[3] == t.trajectories()[2].data()[3]);
  Trainer resumed(ctx, data, cfg, c);
  REQUIRE(resumed.trajectories()[1].data()[7] == t.trajectories()[1].data()[7]);
  std::filesystem::remove(path);
  test::require_no_validation_messages();
}
