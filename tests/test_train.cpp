// The trainer on sharp multi-view data rendered from random ground-truth Gaussians.
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "gpu_fixture.h"
#include "loss/image_losses.h"
#include "splat/synthetic.h"
#include "train/checkpoint.h"
#include "train/trainer.h"

using namespace evflow;

namespace {

// Views on a ring around the ground-truth cloud (centre at depth 6 from the first camera).
io::Dataset make_dataset(gpu::Context& ctx, uint32_t w, uint32_t h, int n_train, int n_novel) {
  io::Dataset d;
  d.layout = "test";
  d.near = 1.0;
  d.far = 12.0;
  Camera c0 = Camera::look_at(w, h, 60.0, {0, 0, 0}, {0, 0, 6}, {0, -1, 0});
  GaussianCloud truth = synthetic_cloud(42, 1500, 0, c0);
  GaussianBuffers gt(ctx, truth.size(), 0, "gt_");
  gt.upload(truth);
  Rasterizer r(ctx);
  for (int i = 0; i < n_train + n_novel; ++i) {
    double ang = (i < n_train ? (i - 0.5 * (n_train - 1)) / n_train : (i - n_train + 0.5 - 0.5 * n_novel) / n_novel * 0.8) * 0.5;
    Camera cam = Camera::look_at(w, h, 60.0, {6 * std::sin(ang), 0.3 * std::cos(3.0 * i), 6 - 6 * std::cos(ang)}, {0, 0, 6}, {0, -1, 0});
    r.forward(gt, cam, RenderSettings{});
    io::View v;
    v.name = (i < n_train ? "train" : "novel") + std::to_string(i);
    v.camera = cam;
    io::Image img = io::image_from_planar_rgb(r.outputs().rgb.read<float>(size_t(w) * h * 3), w, h);
    v.sharp_mid = img;
    if (i < n_train) {
      v.blurry = img;
      d.train.push_back(v);
    } else {
      d.novel.push_back(v);
    }
  }
  return d;
}

double mean_psnr(gpu::Context& ctx, Trainer& t, const std::vector<io::View>& views) {
  double sum = 0;
  for (auto& v : views) {
    auto img = t.render(v.camera);
    auto gt = io::planar_rgb(*v.sharp_mid);
    double mse = 0;
    for (size_t i = 0; i < img.size(); ++i) mse += double(img[i] - gt[i]) * (img[i] - gt[i]);
    sum += -10 * std::log10(mse / img.size());
  }
  return sum / views.size();
}

}  // namespace

TEST_CASE("trainer: fits held-out views of a scene of random Gaussians", "[gpu][train]") {
  auto& ctx = test::gpu_context();
  io::Dataset data = make_dataset(ctx, 200, 150, 12, 4);
  TrainConfig cfg;
  cfg.iterations = 300;
  cfg.init_gaussians = 3000;
  cfg.sh_degree = 0;
  cfg.target = "sharp";
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
  TrainConfig d;
  d.apply_json(c.to_json());
  REQUIRE(d.to_json() == c.to_json());
}
