// The learned exposure's image motion against the simulator's ground truth
// (engine/train/exposure_motion.h): the true trajectory scores no error, the same trajectory run
// backwards is called reversed, a still camera errs by the whole motion.
#include <catch2/catch.hpp>

#include <filesystem>

#include "gpu_fixture.h"
#include "sim/builtin_scenes.h"
#include "sim/simulation_writer.h"
#include "sim/simulator.h"
#include "train/exposure_motion.h"

using namespace evflow;
namespace fs = std::filesystem;

TEST_CASE(
    "exposure motion: the true trajectory scores ~0 px, run backwards it is reversed, still it errs by the motion",
    "[sim][gpu]") {
  auto& ctx = test::gpu_context();
  const sim::Scene scene = sim::make_default_scene();
  sim::SimParams p;
  p.width = 64;
  p.height = 48;
  p.train_views = 1;
  p.novel_views = 0;
  p.blur_px = 6;
  p.seed = 5;
  sim::Simulator s(ctx, scene, p);
  sim::SimResult res = s.run();
  res.scene_source = scene.source;
  const fs::path dir = fs::temp_directory_path() / "evflow_test_exposure_motion";
  fs::remove_all(dir);
  sim::write_simulation(res, dir);
  const sim::TrainViewResult& v = res.train[0];
  const Camera &start = v.poses.front(), &end = v.poses.back();

  const auto right = exposure_motion(dir, v.name, start, v.gt_camera, end);
  REQUIRE(right);
  CHECK(right->pixels > 64 * 48 / 2);
  CHECK(right->truth_px > 3.0);
  CHECK(right->error_px < 0.05 * right->truth_px);
  CHECK_FALSE(right->reversed());
  const auto backwards = exposure_motion(dir, v.name, end, v.gt_camera, start);
  REQUIRE(backwards);
  CHECK(backwards->reversed());
  CHECK(backwards->reversed_error_px == Approx(right->error_px).margin(1e-6));
  const auto still = exposure_motion(dir, v.name, v.gt_camera, v.gt_camera, v.gt_camera);
  REQUIRE(still);
  CHECK(still->error_px == Approx(still->truth_px).epsilon(1e-6));
  // No ground truth: nothing to say.
  fs::remove_all(dir / "gt");
  CHECK_FALSE(exposure_motion(dir, v.name, start, v.gt_camera, end));
  fs::remove_all(dir);
  test::require_no_validation_messages();
}
