// The residual prior (engine/prior): the U-Net's forward against the double reference and its
// gradients (input, every weight and bias) against central differences of that reference at odd
// sizes; the event planes; saving and loading the weights, and the errors for bad files; the
// training rooms and samples; `evflow train-prior`.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include <unistd.h>

#include "cli_helpers.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "prior/event_inputs.h"
#include "prior/residual_net.h"
#include "prior/residual_prior.h"
#include "prior/training_rooms.h"
#include "prior/training_samples.h"
#include "reference/residual_net_reference.h"
#include "sim/builtin_scenes.h"

using namespace evflow;
namespace fs = std::filesystem;

namespace {

std::vector<double> random_values(size_t n, uint32_t seed, double scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (double& x : v) x = double(float(scale * u(rng)));  // exactly representable in float
  return v;
}

std::vector<float> to_float(const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); }

void require_close(const std::vector<float>& got, const std::vector<double>& want, double tol,
                   const std::string& what) {
  REQUIRE(got.size() == want.size());
  double scale = 1e-3;
  for (double w : want) scale = std::max(scale, std::abs(w));
  for (size_t i = 0; i < got.size(); ++i) {
    INFO(what << " [" << i << "]: " << got[i] << " vs " << want[i] << " (largest " << scale << ")");
    REQUIRE(std::abs(double(got[i]) - want[i]) <= tol * (std::abs(want[i]) + 0.1 * scale));
  }
}

// Random weights for every layer of `net`, set on the GPU and returned for the reference.
std::vector<ref::UnetLayer> randomise(prior::ResidualNet& net) {
  std::vector<ref::UnetLayer> layers;
  uint32_t seed = 100;
  for (nn::Conv2d* c : net.layers()) {
    const nn::ConvSpec& s = c->spec();
    ref::UnetLayer l;
    // Uniform weights of about He's spread and positive biases, so that most units are alive.
    l.weight = random_values(c->weight_count(), seed++, 2.5 / std::sqrt(double(s.in_c * s.ksize * s.ksize)));
    l.bias = random_values(s.out_c, seed++, 0.1);
    for (double& b : l.bias) b = double(float(b + 0.2));
    l.out_c = s.out_c, l.ksize = s.ksize, l.stride = s.stride;
    c->set_parameters(to_float(l.weight), to_float(l.bias));
    layers.push_back(l);
  }
  return layers;
}

}  // namespace

TEST_CASE("prior: the residual U-Net's forward and every gradient against the double reference", "[gpu][prior]") {
  auto& ctx = test::gpu_context();
  // 7 x 9: halves to 4 x 5 and 2 x 3, and comes back through both up-sampling rules (2h, 2h - 1).
  prior::ResidualNet net(ctx, {3, 2}, 7, 9);
  REQUIRE(net.input().shape() == nn::Shape{7, 7, 9});
  REQUIRE(net.output().shape() == nn::Shape{6, 7, 9});
  std::vector<ref::UnetLayer> layers = randomise(net);
  ref::NnTensor x(7, 7, 9);
  x.v = random_values(x.v.size(), 1, 1.0);
  const std::vector<double> r = random_values(6 * 7 * 9, 2, 1.0);
  net.input().upload(to_float(x.v));
  net.output_grad().upload(to_float(r));
  gpu::Commands cmd(ctx);
  net.forward(cmd);
  net.backward(cmd, true, false);
  cmd.submit();
  require_close(net.output().download(), ref::residual_unet(x, layers).v, 1e-4, "y");

  auto loss = [&] { return ref::nn_dot(ref::residual_unet(x, layers), r); };
  require_close(net.input_grad().download(), ref::nn_central_differences(x.v, loss, 1e-4), 2e-3, "dx");
  const auto convs = net.layers();
  for (size_t i = 0; i < convs.size(); ++i) {
    const nn::Conv2d& c = *convs[i];
    // Every layer takes part: most of its weight gradient is non-zero.
    const auto g = c.weight_grad().read<float>(c.weight_count());
    INFO(c.name());
    REQUIRE(std::count_if(g.begin(), g.end(), [](float v) { return std::abs(v) > 1e-4f; }) > int(g.size() / 2));
    require_close(c.weight_grad().read<float>(c.weight_count()),
                  ref::nn_central_differences(layers[i].weight, loss, 1e-4), 2e-3, c.name() + ".weight grad");
    require_close(c.bias_grad().read<float>(c.spec().out_c), ref::nn_central_differences(layers[i].bias, loss, 1e-4),
                  2e-3, c.name() + ".bias grad");
  }
  test::require_no_validation_messages();
}

TEST_CASE("prior: the network's size, zero-initialised output and accumulated batch gradients", "[gpu][prior]") {
  auto& ctx = test::gpu_context();
  prior::ResidualNet shipped(ctx, {}, 16, 16);
  CHECK(shipped.spec().str() == "residual-unet frames=7 width=16");
  CHECK(shipped.parameter_count() == 106402);
  prior::ResidualNet net(ctx, {3, 2}, 5, 6);
  net.init_he(3);
  net.input().upload(to_float(random_values(net.input().count(), 4, 1.0)));
  gpu::Commands cmd(ctx);
  net.forward(cmd);
  cmd.submit();
  for (float v : net.output().download()) REQUIRE(v == 0.0f);  // the zero-residual start
  randomise(net);
  net.output_grad().upload(to_float(random_values(net.output().count(), 5, 1.0)));
  net.forward(cmd);
  net.backward(cmd, false, false);
  cmd.submit();
  nn::Conv2d& first = *net.layers().front();
  const auto once = first.weight_grad().read<float>(first.weight_count());
  net.backward(cmd, false, true);
  cmd.submit();
  const auto twice = first.weight_grad().read<float>(first.weight_count());
  for (size_t i = 0; i < once.size(); ++i) REQUIRE(twice[i] == Approx(2 * once[i]).margin(1e-6));
  REQUIRE_THROWS_WITH(prior::ResidualNet(ctx, {4, 2}, 5, 6), Catch::Contains("odd frame count"));
  test::require_no_validation_messages();
}

TEST_CASE("prior: event planes accumulate each polarity from the middle frame, signed by direction", "[prior]") {
  EventStream ev;
  ev.width = 2, ev.height = 1;
  // Frames at 0, 0.5, 1 (N = 1); events at pixel 0 before and after the middle, pixel 1 after.
  ev.push(0, 0, 0.1, +1);
  ev.push(0, 0, 0.2, -1);
  ev.push(0, 0, 0.3, -1);
  ev.push(0, 0, 0.5, +1);  // at t_N: in (t_0, t_N], so in frame 0's window
  ev.push(1, 0, 0.7, +1);
  ev.push(0, 0, 1.0, -1);  // at t_2: in (t_N, t_2]
  const auto p = prior::event_planes(ev, 0.0, 1.0, {0.0, 0.5, 1.0});
  const float s = prior::kEventScale;
  // Planes: frame 0 positive, frame 0 negative, frame 2 positive, frame 2 negative; 2 pixels each.
  REQUIRE(p.size() == 8);
  CHECK(p[0] == Approx(-2 * s));  // two positive events in (0, 0.5], negated for the earlier frame
  CHECK(p[1] == 0.0f);
  CHECK(p[2] == Approx(2 * s));  // two negative events, -1 each, negated
  CHECK(p[3] == 0.0f);
  CHECK(p[4] == 0.0f);
  CHECK(p[5] == Approx(s));
  CHECK(p[6] == Approx(-s));
  CHECK(p[7] == 0.0f);
  REQUIRE_THROWS_WITH(prior::event_planes(ev, 0.0, 1.0, {0.0, 1.0}), Catch::Contains("odd number"));
}

TEST_CASE("prior: weights survive safetensors, and bad files are refused with their name", "[gpu][prior]") {
  auto& ctx = test::gpu_context();
  prior::ResidualNet net(ctx, {3, 2}, 5, 6);
  randomise(net);
  const fs::path path = fs::temp_directory_path() / "evflow_test_prior.safetensors";
  nn::save_safetensors(path, net.save());
  auto other = prior::load_residual_net(ctx, path.string(), 9, 11);
  CHECK(other->spec().str() == net.spec().str());
  for (size_t i = 0; i < net.layers().size(); ++i)
    CHECK(other->layers()[i]->weight_values() == net.layers()[i]->weight_values());
  prior::ResidualNet wider(ctx, {3, 3}, 5, 6);
  REQUIRE_THROWS_WITH(wider.load(nn::load_safetensors(path), "w.safetensors"),
                      Catch::Contains("w.safetensors: architecture 'residual-unet frames=3 width=2'"));
  nn::SafetensorsFile renamed = net.save();
  renamed.tensors[4].name = "prior.other.weight";
  REQUIRE_THROWS_WITH(net.load(renamed, "r.safetensors"), Catch::Contains("r.safetensors: no weights for layer"));
  nn::SafetensorsFile reshaped = net.save();
  reshaped.tensors[1].shape = {1, 2};
  REQUIRE_THROWS_WITH(net.load(reshaped, "s.safetensors"), Catch::Contains("s.safetensors: layer prior.enc0"));
  const auto size = fs::file_size(path);
  fs::resize_file(path, size - 10);
  REQUIRE_THROWS_WITH(prior::load_residual_net(ctx, path.string(), 5, 6), Catch::Contains(path.string()));
  fs::remove(path);
  REQUIRE_THROWS_WITH(prior::load_residual_net(ctx, path.string(), 5, 6), Catch::Contains(path.string()));
  test::require_no_validation_messages();
}

TEST_CASE("prior: training rooms are seeded and not the built-in scenes, and samples hold exact residuals",
          "[gpu][prior]") {
  const sim::Scene a = prior::make_training_room(1000), b = prior::make_training_room(1000),
                   c = prior::make_training_room(1001);
  CHECK(a.positions == b.positions);
  CHECK(a.positions != c.positions);
  for (const std::string& name : sim::builtin_scene_names())
    CHECK(sim::make_builtin_scene(name).positions != a.positions);
  prior::SampleOptions o;
  o.width = 48, o.height = 36, o.views_per_room = 1, o.blur_min_px = o.blur_max_px = 6;
  const auto samples = prior::simulate_samples(test::gpu_context(), {1000}, o, true);
  REQUIRE(samples.size() == 1);
  const prior::PriorSample& s = samples[0];
  const size_t hw = 48 * 36;
  REQUIRE(s.input.size() == 15 * hw);
  REQUIRE(s.target.size() == 18 * hw);
  REQUIRE(s.edi_residual.size() == 18 * hw);
  double events = 0, zero = 0, edi = 0, late = 0, early = 0;
  for (size_t i = 3 * hw; i < s.input.size(); ++i) events += std::abs(s.input[i]);
  for (size_t i = 0; i < s.target.size(); ++i) {
    zero += double(s.target[i]) * s.target[i];
    edi += double(s.edi_residual[i] - s.target[i]) * (s.edi_residual[i] - s.target[i]);
  }
  // The frames furthest from the middle change most: R(t_0) and R(t_6) against R(t_2) and R(t_4).
  for (size_t i = 0; i < 3 * hw; ++i) late += std::abs(s.target[i]) + std::abs(s.target[15 * hw + i]);
  for (size_t i = 6 * hw; i < 12 * hw; ++i) early += std::abs(s.target[i]);
  INFO("event planes " << events << ", residual energy " << zero << ", EDI error " << edi);
  CHECK(events > 0);
  CHECK(zero > 0);
  CHECK(edi < zero);  // EDI's residual is informative on noise-free simulated events
  CHECK(late > early);
  const prior::Crop cr = prior::crop(s, 5, 3, 16);
  CHECK(cr.input[0] == s.input[3 * 48 + 5]);
  CHECK(cr.target[18 * 256 - 1] == s.target[17 * hw + 18 * 48 + 20]);
  REQUIRE_THROWS_WITH(prior::crop(s, 40, 0, 16), Catch::Contains("outside"));
  test::require_no_validation_messages();
}

TEST_CASE("prior: evflow train-prior trains, scores against both baselines and writes its weights", "[gpu][prior]") {
  REQUIRE(fs::exists(test::evflow_binary()));
  const fs::path dir = evflow::test::fresh_dir("evflow_train_prior");
  std::string out;
  const std::string args =
      "train-prior --out w.safetensors --rooms 1 --held-out-rooms 1 --views 1 --width 40 --height 32 --crop 16 "
      "--steps 4 --batch 2 --net-width 2 --log-every 2";
  REQUIRE(test::run_evflow(dir, args, out) == 0);
  INFO(out);
  CHECK(out.find("step 4  loss") != std::string::npos);
  CHECK(out.find("held-out residual MSE over") != std::string::npos);
  const nn::SafetensorsFile f = nn::load_safetensors(dir / "w.safetensors");
  CHECK(f.metadata.at("architecture") == "residual-unet frames=7 width=2");
  CHECK(f.metadata.at("command") == "evflow " + args);
  CHECK(f.metadata.at("steps") == "4");
  // The held-out scores of the network and of both baselines: positive, and EDI's residuals
  // nearer the truth than none at all.
  const double mse = std::stod(f.metadata.at("heldout_mse")), zero = std::stod(f.metadata.at("heldout_mse_zero")),
               edi = std::stod(f.metadata.at("heldout_mse_edi"));
  CHECK(std::isfinite(mse));
  CHECK(mse > 0);
  CHECK(zero > 0);
  CHECK(edi > 0);
  CHECK(edi < zero);
  CHECK(test::run_evflow(dir, "train-prior --rooms 1", out) != 0);
  CHECK(out.find("--out FILE.safetensors is required") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("prior: the shipped weights load as the default network and stay small", "[gpu][prior]") {
  const std::string path = prior::resolve_weights_path("assets/residual_prior.safetensors");
  REQUIRE(fs::exists(path));
  CHECK(fs::file_size(path) <= 5u * 1024 * 1024);
  auto net = prior::load_residual_net(test::gpu_context(), path, 13, 17);
  CHECK(net->spec().str() == prior::ResidualNetSpec{}.str());
  const nn::SafetensorsFile f = nn::load_safetensors(path);
  CHECK(f.metadata.at("command").rfind("evflow train-prior ", 0) == 0);
  test::require_no_validation_messages();
}
