// The learned exposure's image motion against the simulator's ground truth
// (engine/train/exposure_motion.h): the true trajectory scores no error, the same trajectory run
// backwards is called reversed, a still camera errs by the whole motion, a turned mid-exposure
// camera is misplaced by the turn.
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
    "exposure motion: the true trajectory scores ~0 px, run backwards it is reversed, still it errs by the motion, "
    "turned at mid-exposure it is misplaced",
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
  // The true mid-exposure camera is in place; turned by 0.01 rad about its y axis, the learned one
  // sees every point about fx * 0.01 px away (more towards the image's sides).
  CHECK(right->mid_error_px < 1e-3);
  const double turn = 0.01;
  const auto turned = exposure_motion(dir, v.name, start, v.gt_camera.perturbed({0, 0, 0, 0, turn, 0}), end);
  REQUIRE(turned);
  CHECK(turned->mid_error_px > v.gt_camera.fx * turn);
  CHECK(turned->mid_error_px < 1.3 * v.gt_camera.fx * turn);
  // No ground truth: nothing to say.
  fs::remove_all(dir / "gt");
  CHECK_FALSE(exposure_motion(dir, v.name, start, v.gt_camera, end));
  fs::remove_all(dir);
  test::require_no_validation_messages();
}
