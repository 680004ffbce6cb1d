// The neural layers (engine/nn): each layer's forward against the double reference, its
// gradients (input, weights, bias) against central differences of that reference, at odd sizes
// and on both GEMM tilings; He initialisation, Adam on a small regression, determinism.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>

#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "nn/conv2d.h"
#include "nn/conv_stack.h"
#include "nn/he_init.h"
#include "nn/layers.h"
#include "reference/nn_reference.h"

using namespace evflow;
using ref::NnTensor;
namespace fs = std::filesystem;

namespace {

std::vector<double> random_values(size_t n, uint32_t seed, double scale = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (double& x : v) x = scale * u(rng);
  return v;
}

std::vector<float> to_float(const std::vector<double>& v) { return std::vector<float>(v.begin(), v.end()); }

// Rounds to float and back, so that the reference sees exactly what the GPU sees.
void round_to_float(std::vector<double>& v) {
  for (double& x : v) x = double(float(x));
}

void require_close(const std::vector<float>& got, const std::vector<double>& want, double tol, const char* what) {
  REQUIRE(got.size() == want.size());
  double scale = 1e-3;
  for (double w : want) scale = std::max(scale, std::abs(w));
  for (size_t i = 0; i < got.size(); ++i) {
    INFO(what << " [" << i << "]: " << got[i] << " vs " << want[i] << " (largest " << scale << ")");
    REQUIRE(std::abs(double(got[i]) - want[i]) <= tol * (std::abs(want[i]) + 0.1 * scale));
  }
}

nn::Tensor upload(const NnTensor& t, const char* name) {
  nn::Tensor d(test::gpu_context(), {t.c, t.h, t.w}, name);
  d.upload(to_float(t.v));
  return d;
}

struct ConvCase {
  uint32_t in_c, out_c, ksize, stride, h, w;
};

// One conv on the GPU: forward, then backward of L = sum r y; checked against the reference.
void check_conv(const ConvCase& cs) {
  auto& ctx = test::gpu_context();
  INFO("conv " << cs.in_c << "->" << cs.out_c << " k" << cs.ksize << " s" << cs.stride << " " << cs.w << "x" << cs.h);
  NnTensor x(cs.in_c, cs.h, cs.w);
  x.v = random_values(x.v.size(), 1);
  std::vector<double> w = random_values(size_t(cs.out_c) * cs.in_c * cs.ksize * cs.ksize, 2, 0.5);
  std::vector<double> b = random_values(cs.out_c, 3);
  round_to_float(x.v), round_to_float(w), round_to_float(b);
  const NnTensor y = ref::nn_conv2d(x, w, b, cs.out_c, cs.ksize, cs.stride);
  std::vector<double> r = random_values(y.v.size(), 4);
  round_to_float(r);

  nn::Conv2d conv(ctx, {cs.in_c, cs.out_c, cs.ksize, cs.stride}, "conv");
  conv.set_parameters(to_float(w), to_float(b));
  nn::Tensor dx_in = upload(x, "x"), dy(ctx, {y.c, y.h, y.w}, "dy"), gy(ctx, dy.shape(), "y"),
             dx(ctx, dx_in.shape(), "dx");
  dy.upload(to_float(r));
  gpu::Commands cmd(ctx);
  conv.forward(cmd, dx_in, gy);
  conv.backward(cmd, dx_in, dy, &dx);
  cmd.submit();
  require_close(gy.download(), y.v, 1e-4, "y");

  auto loss = [&] { return ref::nn_dot(ref::nn_conv2d(x, w, b, cs.out_c, cs.ksize, cs.stride), r); };
  require_close(dx.download(), ref::nn_central_differences(x.v, loss, 1e-3), 1e-3, "dx");
  require_close(conv.weight_grad().read<float>(w.size()), ref::nn_central_differences(w, loss, 1e-3), 1e-3, "dw");
  require_close(conv.bias_grad().read<float>(b.size()), ref::nn_central_differences(b, loss, 1e-3), 1e-3, "db");
  test::require_no_validation_messages();
}

// A batch: `images` images of a tensor that holds `capacity`, one forward and backward over
// them; each image's output against the reference of that image alone, the weight and bias
// gradients against central differences of the sum over the images, dx (with check_dx) too.
void check_conv_batch(const ConvCase& cs, uint32_t images, uint32_t capacity, bool check_dx) {
  auto& ctx = test::gpu_context();
  INFO("batch of " << images << " in " << capacity << ": conv " << cs.in_c << "->" << cs.out_c << " k" << cs.ksize
                   << " s" << cs.stride << " " << cs.w << "x" << cs.h);
  std::vector<NnTensor> xs(images, NnTensor(cs.in_c, cs.h, cs.w));
  for (uint32_t b = 0; b < images; ++b) xs[b].v = random_values(xs[b].v.size(), 20 + b), round_to_float(xs[b].v);
  std::vector<double> w = random_values(size_t(cs.out_c) * cs.in_c * cs.ksize * cs.ksize, 2, 0.5);
  std::vector<double> b = random_values(cs.out_c, 3);
  round_to_float(w), round_to_float(b);
  const NnTensor y0 = ref::nn_conv2d(xs[0], w, b, cs.out_c, cs.ksize, cs.stride);
  std::vector<std::vector<double>> rs(images);
  for (uint32_t i = 0; i < images; ++i) rs[i] = random_values(y0.v.size(), 40 + i), round_to_float(rs[i]);

  auto concat = [&](auto part) {
    std::vector<double> all;
    for (uint32_t i = 0; i < images; ++i) {
      const std::vector<double>& v = part(i);
      all.insert(all.end(), v.begin(), v.end());
    }
    return all;
  };
  const std::vector<double> x_all = concat([&](uint32_t i) -> const std::vector<double>& { return xs[i].v; });
  const std::vector<double> r_all = concat([&](uint32_t i) -> const std::vector<double>& { return rs[i]; });
  std::vector<float> x_up = to_float(x_all), r_up = to_float(r_all);
  nn::Tensor gx(ctx, {cs.in_c, cs.h, cs.w, capacity}, "x"), dx(ctx, gx.shape(), "dx");
  nn::Tensor gy(ctx, {y0.c, y0.h, y0.w, capacity}, "y"), dy(ctx, gy.shape(), "dy");
  x_up.resize(gx.count(), 7.0f), r_up.resize(dy.count(), 7.0f);  // images past the batch: must not count
  gx.upload(x_up), dy.upload(r_up);
  nn::Conv2d conv(ctx, {cs.in_c, cs.out_c, cs.ksize, cs.stride}, "conv");
  conv.set_parameters(to_float(w), to_float(b));
  gpu::Commands cmd(ctx);
  conv.forward(cmd, gx, gy, images);
  conv.backward(cmd, gx, dy, &dx, false, false, images);
  cmd.submit();
  std::vector<float> y = gy.download(), g = dx.download();
  for (uint32_t i = 0; i < images; ++i) {
    const NnTensor want = ref::nn_conv2d(xs[i], w, b, cs.out_c, cs.ksize, cs.stride);
    require_close(std::vector<float>(y.begin() + i * want.v.size(), y.begin() + (i + 1) * want.v.size()), want.v, 1e-4,
                  "y");
  }
  auto loss = [&] {
    double l = 0;
    for (uint32_t i = 0; i < images; ++i)
      l += ref::nn_dot(ref::nn_conv2d(xs[i], w, b, cs.out_c, cs.ksize, cs.stride), rs[i]);
    return l;
  };
  require_close(conv.weight_grad().read<float>(w.size()), ref::nn_central_differences(w, loss, 1e-3), 1e-3, "dw");
  require_close(conv.bias_grad().read<float>(b.size()), ref::nn_central_differences(b, loss, 1e-3), 1e-3, "db");
  if (check_dx)
    for (uint32_t i = 0; i < images; ++i) {
      const size_t n = xs[i].v.size();
      require_close(std::vector<float>(g.begin() + i * n, g.begin() + (i + 1) * n),
                    ref::nn_central_differences(xs[i].v, loss, 1e-3), 1e-3, "dx");
    }
  test::require_no_validation_messages();
}

}  // namespace

TEST_CASE("nn: 3x3 and 1x1 convolutions, stride 1 and 2, forward and gradients at odd sizes", "[gpu][nn]") {
  // Narrow tiling (<= 16 output channels) and wide; several k tiles (in_c 7: K = 63) and n tiles.
  for (const ConvCase& c : {ConvCase{3, 5, 3, 1, 9, 13}, ConvCase{3, 5, 3, 2, 9, 13}, ConvCase{3, 5, 1, 1, 9, 13},
                            ConvCase{3, 5, 1, 2, 9, 13}, ConvCase{7, 33, 3, 1, 11, 17}, ConvCase{7, 70, 3, 2, 11, 17},
                            ConvCase{4, 1, 3, 1, 23, 29}})
    check_conv(c);
}

TEST_CASE("nn: the direct 3x3 convolution (CPU drivers) at widths of whole vec4s, edges and partial groups",
          "[gpu][nn]") {
  // 3x3 stride-1 layers with 8 or more output channels take the direct kernel on CPU drivers (its
  // input gradient with 8 or more input channels), rows as vec4s where the width is a multiple of
  // 4: one column of blocks (w 4), heights not a multiple of its 4 rows, 20 and 9 channels (a
  // partial group of 16), a 32-channel input; widths 13 and 6 (one value per access, a partial
  // last column of blocks).
  for (const ConvCase& c : {ConvCase{5, 8, 3, 1, 10, 12}, ConvCase{9, 20, 3, 1, 7, 8}, ConvCase{16, 16, 3, 1, 6, 4},
                            ConvCase{32, 8, 3, 1, 3, 8}, ConvCase{9, 12, 3, 1, 5, 13}, ConvCase{8, 8, 3, 1, 9, 6}})
    check_conv(c);
  check_conv_batch({8, 12, 3, 1, 5, 8}, 3, 4, true);  // the first 3 images of a batch of 4
  check_conv_batch({8, 9, 3, 1, 4, 7}, 2, 3, true);
}

TEST_CASE("nn: a batch of images runs as one convolution, each image padded on its own", "[gpu][nn]") {
  // Images of 9 x 13 pixels: the GEMM's 128-pixel tiles and its vec4 loads straddle images.
  check_conv_batch({3, 5, 3, 1, 9, 13}, 3, 3, true);
  check_conv_batch({3, 5, 3, 2, 9, 13}, 3, 4, true);  // the first 3 images of a batch of 4
  check_conv_batch({7, 33, 3, 1, 11, 17}, 2, 2, false);
  // 5 images of 25 x 40: 5000 output pixels, three splits of the weight gradient's partial sums.
  check_conv_batch({2, 3, 3, 1, 25, 40}, 5, 5, false);
}

namespace {

// Two backward passes of an in_c -> out_c 3x3 convolution over an h x w image, the second adding
// into the first's dx, weight and bias gradients: each gradient must be twice the reference.
void check_accumulating(uint32_t in_c, uint32_t out_c, uint32_t h, uint32_t w, uint64_t seed) {
  auto& ctx = test::gpu_context();
  INFO("conv " << in_c << "->" << out_c << " " << w << "x" << h);
  NnTensor x(in_c, h, w);
  x.v = random_values(x.v.size(), seed);
  std::vector<double> wt = random_values(size_t(out_c) * in_c * 9, seed + 1, 0.5), b = random_values(out_c, seed + 2);
  round_to_float(x.v), round_to_float(wt), round_to_float(b);
  std::vector<double> r = random_values(size_t(out_c) * h * w, seed + 3);
  round_to_float(r);
  nn::Conv2d conv(ctx, {in_c, out_c, 3, 1}, "conv");
  conv.set_parameters(to_float(wt), to_float(b));
  nn::Tensor gx = upload(x, "x"), dy(ctx, {out_c, h, w}, "dy"), dx(ctx, gx.shape(), "dx");
  dy.upload(to_float(r));
  gpu::Commands cmd(ctx);
  conv.backward(cmd, gx, dy, &dx);
  conv.backward(cmd, gx, dy, &dx, true, true);  // adds the same gradients again
  cmd.submit();
  auto loss = [&] { return 2.0 * ref::nn_dot(ref::nn_conv2d(x, wt, b, out_c, 3, 1), r); };
  require_close(conv.weight_grad().read<float>(wt.size()), ref::nn_central_differences(wt, loss, 1e-3), 1e-3, "dw");
  require_close(conv.bias_grad().read<float>(out_c), ref::nn_central_differences(b, loss, 1e-3), 1e-3, "db");
  require_close(dx.download(), ref::nn_central_differences(x.v, loss, 1e-3), 1e-3, "dx");
  test::require_no_validation_messages();
}

}  // namespace

TEST_CASE("nn: the weight gradient over several pixel splits and the accumulating forms", "[gpu][nn]") {
  check_accumulating(2, 3, 40, 65, 5);  // 2600 output pixels: two splits of the weight gradient's partial sums
  check_accumulating(8, 4, 6, 12, 9);   // 8 input channels: the direct kernel's input gradient (CPU drivers)
  // 8 output channels: the direct weight gradient (CPU drivers), over 144 blocks of 4 x 4 pixels:
  // two splits of 128 blocks.
  check_accumulating(1, 8, 36, 64, 17);
}

TEST_CASE("nn: the backward is deterministic (no atomics): two runs give the same bits", "[gpu][nn]") {
  auto& ctx = test::gpu_context();
  nn::Conv2d conv(ctx, {8, 24, 3, 1}, "conv");
  conv.init_he(3);
  NnTensor x(8, 50, 61);
  x.v = random_values(x.v.size(), 9);
  nn::Tensor gx = upload(x, "x"), dy(ctx, {24, 50, 61}, "dy"), dx(ctx, gx.shape(), "dx");
  dy.upload(to_float(random_values(dy.count(), 10)));
  std::vector<float> first_w, first_x;
  for (int run = 0; run < 2; ++run) {
    gpu::Commands cmd(ctx);
    conv.backward(cmd, gx, dy, &dx);
    cmd.submit();
    auto w = conv.weight_grad().read<float>(conv.weight_count());
    auto d = dx.download();
    if (run == 0) first_w = w, first_x = d;
    REQUIRE(std::memcmp(w.data(), first_w.data(), w.size() * 4) == 0);
    REQUIRE(std::memcmp(d.data(), first_x.data(), d.size() * 4) == 0);
  }
  test::require_no_validation_messages();
}

namespace {

// An element-wise layer's forward and input gradient (L = sum r y), against the reference.
void check_pointwise(const char* what, const NnTensor& x, uint32_t out_h, uint32_t out_w,
                     const std::function<NnTensor(const NnTensor&)>& reference) {
  auto& ctx = test::gpu_context();
  INFO(what);
  NnTensor xr = x;
  const NnTensor y = reference(xr);
  REQUIRE((y.h == out_h && y.w == out_w));
  std::vector<double> r = random_values(y.v.size(), 11);
  round_to_float(r);
  nn::Tensor gx = upload(x, "x"), gy(ctx, {y.c, y.h, y.w}, "y"), dy(ctx, gy.shape(), "dy"), dx(ctx, gx.shape(), "dx");
  dy.upload(to_float(r));
  gpu::Commands cmd(ctx);
  const std::string name = what;
  if (name == "relu") {
    nn::relu_forward(cmd, gx, gy);
    nn::relu_backward(cmd, gy, dy, dx);
  } else if (name == "sigmoid") {
    nn::sigmoid_forward(cmd, gx, gy);
    nn::sigmoid_backward(cmd, gy, dy, dx);
  } else {
    nn::upsample_forward(cmd, gx, gy);
    nn::upsample_backward(cmd, dy, dx);
  }
  cmd.submit();
  require_close(gy.download(), y.v, 1e-5, "y");
  auto loss = [&] { return ref::nn_dot(reference(xr), r); };
  require_close(dx.download(), ref::nn_central_differences(xr.v, loss, 1e-4), 1e-3, "dx");
  test::require_no_validation_messages();
}

}  // namespace

TEST_CASE("nn: ReLU, sigmoid and x2 up-sampling, forward and input gradient", "[gpu][nn]") {
  NnTensor x(5, 9, 13);
  x.v = random_values(x.v.size(), 12, 4.0);
  for (double& v : x.v) v = std::abs(v) < 0.01 ? 0.5 : v;  // away from ReLU's kink
  round_to_float(x.v);
  check_pointwise("relu", x, 9, 13, ref::nn_relu);
  check_pointwise("sigmoid", x, 9, 13, ref::nn_sigmoid);
  // Odd sizes: 9 x 13 to 17 x 25 (a stride-2 convolution's 17 x 25 coming back), and to 18 x 26.
  check_pointwise("upsample", x, 17, 25, [](const NnTensor& t) { return ref::nn_upsample(t, 17, 25); });
  check_pointwise("upsample", x, 18, 26, [](const NnTensor& t) { return ref::nn_upsample(t, 18, 26); });
}

TEST_CASE("nn: sigmoid stays finite at large inputs, and up-sampling refuses other sizes", "[gpu][nn]") {
  auto& ctx = test::gpu_context();
  nn::Tensor x(ctx, {1, 1, 4}, "x"), y(ctx, {1, 1, 4}, "y"), big(ctx, {1, 3, 9}, "big");
  x.upload({-200.0f, -90.0f, 90.0f, 200.0f});
  gpu::Commands cmd(ctx);
  nn::sigmoid_forward(cmd, x, y);
  cmd.submit();
  const auto v = y.download();
  CHECK(v[0] == 0.0f);
  CHECK(v[1] >= 0.0f);
  CHECK(v[2] == 1.0f);
  CHECK(v[3] == 1.0f);
  REQUIRE_THROWS_WITH(nn::upsample_forward(cmd, x, big), Catch::Contains("cannot be up-sampled"));
  test::require_no_validation_messages();
}

TEST_CASE("nn: channel concatenation and its backward split", "[gpu][nn]") {
  auto& ctx = test::gpu_context();
  nn::Tensor a(ctx, {2, 3, 5}, "a"), b(ctx, {3, 3, 5}, "b"), y(ctx, {5, 3, 5}, "y");
  nn::Tensor da(ctx, a.shape(), "da"), db(ctx, b.shape(), "db");
  const auto va = to_float(random_values(a.count(), 13)), vb = to_float(random_values(b.count(), 14));
  a.upload(va);
  b.upload(vb);
  gpu::Commands cmd(ctx);
  nn::concat_forward(cmd, a, b, y);
  nn::concat_backward(cmd, y, da, db);
  cmd.submit();
  std::vector<float> want = va;
  want.insert(want.end(), vb.begin(), vb.end());
  CHECK(y.download() == want);
  CHECK(da.download() == va);
  CHECK(db.download() == vb);
  REQUIRE_THROWS_WITH(nn::concat_forward(cmd, a, y, y), Catch::Contains("expected"));
  test::require_no_validation_messages();
}

TEST_CASE("nn: He initialisation: N(0, 2 / fan_in), seeded and repeatable", "[nn][init]") {
  const uint32_t fan_in = 64 * 9;
  const auto v = nn::he_normal(128 * 64 * 9, fan_in, 7);
  double mean = 0, sq = 0;
  for (float x : v) mean += x, sq += double(x) * x;
  mean /= v.size();
  const double sd = std::sqrt(sq / v.size() - mean * mean), want = std::sqrt(2.0 / fan_in);
  CHECK(std::abs(mean) < 4 * want / std::sqrt(double(v.size())));
  CHECK(std::abs(sd / want - 1) < 0.01);
  size_t beyond = 0;  // about 4.55 % lie beyond two standard deviations
  for (float x : v) beyond += std::abs(x) > 2 * want;
  CHECK(std::abs(double(beyond) / v.size() - 0.0455) < 0.003);
  CHECK(nn::he_normal(1000, fan_in, 7) == std::vector<float>(v.begin(), v.begin() + 1000));
  CHECK(nn::he_normal(1000, fan_in, 8) != std::vector<float>(v.begin(), v.begin() + 1000));
}

TEST_CASE("nn: Adam on a 3x3 convolution fits a target convolution", "[gpu][nn]") {
  auto& ctx = test::gpu_context();
  NnTensor x(2, 11, 14);
  x.v = random_values(x.v.size(), 15);
  round_to_float(x.v);
  const std::vector<double> tw = random_values(2 * 2 * 9, 16, 0.5), tb = random_values(2, 17);
  const NnTensor target = ref::nn_conv2d(x, tw, tb, 2, 3, 1);
  nn::Conv2d conv(ctx, {2, 2, 3, 1}, "fit");
  conv.init_he(1);
  AdamOptions o;
  o.eps = 1e-8;
  Adam adam(ctx, o);
  conv.add_to(adam, 0.02f);
  nn::Tensor gx = upload(x, "x"), y(ctx, {2, 11, 14}, "y"), dy(ctx, y.shape(), "dy");
  double first = 0, last = 0;
  std::vector<float> g(y.count());
  for (int step = 0; step < 400; ++step) {
    gpu::Commands cmd(ctx);
    conv.forward(cmd, gx, y);
    cmd.submit();
    const auto out = y.download();
    double loss = 0;
    for (size_t i = 0; i < out.size(); ++i) {
      const double e = out[i] - target.v[i];
      loss += e * e / out.size();
      g[i] = float(2 * e / out.size());
    }
    (step == 0 ? first : last) = loss;
    dy.upload(g);
    conv.backward(cmd, gx, dy, nullptr);
    adam.step(cmd);
    cmd.submit();
  }
  INFO("loss " << first << " -> " << last);
  CHECK(last < 1e-6 * first);
  require_close(conv.weight_values(), tw, 1e-2, "fitted weights");
  test::require_no_validation_messages();
}

TEST_CASE("nn: a conv stack (conv, ReLU, conv) matches the reference and survives safetensors", "[gpu][nn]") {
  auto& ctx = test::gpu_context();
  nn::ConvStack stack(ctx, {3, 6, 1}, 9, 13, "ldi");
  stack.init_he(5);
  NnTensor x(3, 9, 13);
  x.v = random_values(x.v.size(), 18);
  round_to_float(x.v);
  stack.input().upload(to_float(x.v));
  gpu::Commands cmd(ctx);
  stack.forward(cmd);
  cmd.submit();
  auto values = [](const std::vector<float>& v) { return std::vector<double>(v.begin(), v.end()); };
  nn::Conv2d& c0 = stack.layer(0);
  nn::Conv2d& c1 = stack.layer(1);
  const NnTensor h = ref::nn_relu(ref::nn_conv2d(x, values(c0.weight_values()), values(c0.bias_values()), 6, 3, 1));
  const NnTensor y = ref::nn_conv2d(h, values(c1.weight_values()), values(c1.bias_values()), 1, 3, 1);
  const auto out = stack.output().download();
  require_close(out, y.v, 1e-4, "stack output");

  nn::SafetensorsFile file;
  stack.save(file);
  const fs::path path = fs::temp_directory_path() / "evflow_test_stack.safetensors";
  nn::save_safetensors(path, file);
  nn::ConvStack other(ctx, {3, 6, 1}, 9, 13, "ldi");
  other.init_he(99);
  other.load(nn::load_safetensors(path), path.string());
  fs::remove(path);
  other.input().upload(to_float(x.v));
  other.forward(cmd);
  cmd.submit();
  CHECK(other.output().download() == out);
  nn::ConvStack wider(ctx, {3, 7, 1}, 9, 13, "ldi");
  REQUIRE_THROWS_WITH(wider.load(file, "w.safetensors"), Catch::Contains("w.safetensors: layer ldi.0"));
  test::require_no_validation_messages();
}
