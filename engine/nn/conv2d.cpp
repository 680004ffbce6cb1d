#include "nn/conv2d.h"

#include <algorithm>
#include <stdexcept>

#include "nn/he_init.h"
#include "nn/nn_layout.h"

namespace evflow::nn {

using namespace shaderio;

namespace {

// Output pixels per split of the weight gradient's reduction over pixels.
constexpr uint32_t kPixelsPerSplit = 2048;

// The GEMM's tile by its row count m (nn_layout.h): tiny, narrow or wide.
bool tiny(uint32_t m) { return m <= kGemmTinyTileM; }
bool narrow(uint32_t m) { return m <= 16; }
uint32_t tile_m(uint32_t m) { return tiny(m) ? kGemmTinyTileM : narrow(m) ? kGemmNarrowTileM : kGemmTileM; }
uint32_t tile_n(uint32_t m) { return tiny(m) ? kGemmTinyTileN : narrow(m) ? kGemmNarrowTileN : kGemmTileN; }

// The GEMM's push constants for a convolution of x (in) to y (out), with m, n, k and the tiling.
ConvPC conv_pc(const ConvSpec& s, const Shape& in, const Shape& out, uint32_t m, uint32_t n, uint32_t k) {
  ConvPC pc{};
  pc.in_c = in.c, pc.in_h = in.h, pc.in_w = in.w;
  pc.out_c = out.c, pc.out_h = out.h, pc.out_w = out.w;
  pc.ksize = s.ksize, pc.stride = s.stride, pc.pad = s.ksize / 2;
  pc.gemm_m = m, pc.gemm_n = n, pc.gemm_k = k;
  pc.tiles_n = gpu::Commands::div_up(n, tile_n(m));
  return pc;
}

gpu::Groups tile_groups(gpu::Commands& cmd, const ConvPC& pc) {
  return cmd.linear_groups(uint64_t(gpu::Commands::div_up(pc.gemm_m, tile_m(pc.gemm_m))) * pc.tiles_n);
}

std::string kernel(const char* base, uint32_t m) {
  return std::string("nn/") + base + (tiny(m) ? "_tiny" : narrow(m) ? "_narrow" : "");
}

// The direct kernels' geometry: the full one, or under GPU-assisted validation the "_checked"
// builds' small one (nn_layout.h).
struct DirectGeometry {
  uint32_t rows, group;
  const char* suffix;
};
DirectGeometry direct_geometry(const gpu::Context& ctx) {
  if (ctx.options().gpu_validation) return {kDirectRowsChecked, kDirectGroupChecked, "_checked"};
  return {kDirectRows, kDirectGroup, ""};
}

// The direct kernel's build for images `width` wide: rows as vec4s or one value per access.
std::string direct_kernel(const gpu::Context& ctx, const char* base, uint32_t width) {
  return std::string("nn/") + base + (width % 4 == 0 ? "" : "_any") + direct_geometry(ctx).suffix;
}

// Channels rounded up to whole groups of `group` (a multiple of 4).
uint32_t pad_group(uint32_t c, uint32_t group = kDirectGroup) { return (c + group - 1) / group * group; }

}  // namespace

Conv2d::Conv2d(gpu::Context& ctx, ConvSpec spec, std::string name) : ctx_(ctx), spec_(spec), name_(std::move(name)) {
  if (spec.ksize != 1 && spec.ksize != 3) throw std::invalid_argument("conv " + name_ + ": ksize must be 1 or 3");
  if (spec.stride != 1 && spec.stride != 2) throw std::invalid_argument("conv " + name_ + ": stride must be 1 or 2");
  if (spec.in_c == 0 || spec.out_c == 0) throw std::invalid_argument("conv " + name_ + ": no channels");
  const uint32_t shared = std::max(kGemmSharedBytes, kGemmNarrowSharedBytes);
  if (ctx.caps().max_shared_memory < shared)
    throw gpu::Error("conv " + name_ + ": the GEMM tiles need " + std::to_string(shared) + " bytes of shared memory, " +
                     ctx.caps().name + " has " + std::to_string(ctx.caps().max_shared_memory));
  ctx.check_binding_size(weight_count() * 4, "conv " + name_ + " weights");
  weight_ = gpu::Buffer(ctx, weight_count() * 4, name_ + ".weight");
  bias_ = gpu::Buffer(ctx, spec.out_c * 4, name_ + ".bias");
  weight_grad_ = gpu::Buffer(ctx, weight_count() * 4, name_ + ".weight_grad");
  bias_grad_ = gpu::Buffer(ctx, spec.out_c * 4, name_ + ".bias_grad");
  partial_ = gpu::Buffer(ctx, 16, name_ + ".partial_sums");
  // The direct kernels' rearranged weights, where they can run (placeholders elsewhere).
  const bool any_direct = direct(spec.out_c) || direct(spec.in_c);
  weight_t_ =
      gpu::Buffer(ctx, any_direct ? uint64_t(spec.in_c) * 9 * pad_group(spec.out_c) * 4 : 16, name_ + ".weight_t");
  weight_tb_ =
      gpu::Buffer(ctx, any_direct ? uint64_t(spec.out_c) * 9 * pad_group(spec.in_c) * 4 : 16, name_ + ".weight_tb");
  init_he(0);
}

Shape Conv2d::output_shape(const Shape& in) const {
  if (in.c != spec_.in_c)
    throw std::invalid_argument("conv " + name_ + ": input has " + std::to_string(in.c) + " channels, expected " +
                                std::to_string(spec_.in_c));
  return {spec_.out_c, (in.h + spec_.stride - 1) / spec_.stride, (in.w + spec_.stride - 1) / spec_.stride, in.n};
}

uint64_t Conv2d::macs(const Shape& in) const { return output_shape(in).count() / spec_.out_c * weight_count(); }

Shape Conv2d::run_shape(const Tensor& x, uint32_t images) const {
  const Shape& s = x.shape();
  if (images > s.n)
    throw std::invalid_argument("conv " + name_ + ": " + std::to_string(images) + " images asked of " + x.name() +
                                " (" + s.str() + ")");
  return s.batch(images ? images : s.n);
}

// The partial sums' bytes for a backward over `in`, and the split: output pixels per split of the
// GEMM, or blocks per split of the direct kernel (direct(out_c)); splits double until the sums fit
// one binding.
uint64_t Conv2d::partial_bytes(const Shape& in, uint32_t* per_split_count) const {
  const Shape out = output_shape(in);
  const uint64_t per_split = uint64_t(spec_.out_c) * (spec_.in_c * spec_.ksize * spec_.ksize + 1) * 4;
  const bool blocks = direct(spec_.out_c);
  const uint64_t units = blocks ? uint64_t(gpu::Commands::div_up(out.w, 4)) *
                                      gpu::Commands::div_up(out.h, direct_geometry(ctx_).rows) * out.n
                                : out.count() / out.c;
  uint32_t count = blocks ? kDirectBlocksPerSplit : kPixelsPerSplit;
  while (per_split * gpu::Commands::div_up(units, count) > ctx_.caps().max_storage_buffer_range) count *= 2;
  if (per_split_count) *per_split_count = count;
  return per_split * gpu::Commands::div_up(units, count);
}

void Conv2d::reserve(const Shape& in) { partial_.ensure(partial_bytes(in, nullptr)); }

void Conv2d::init_he(uint64_t seed) {
  set_parameters(he_normal(weight_count(), spec_.in_c * spec_.ksize * spec_.ksize, seed),
                 std::vector<float>(spec_.out_c, 0.0f));
}

void Conv2d::set_parameters(const std::vector<float>& weight, const std::vector<float>& bias) {
  if (weight.size() != weight_count() || bias.size() != spec_.out_c)
    throw std::invalid_argument("conv " + name_ + ": " + std::to_string(weight.size()) + " weights and " +
                                std::to_string(bias.size()) + " biases given, expected " +
                                std::to_string(weight_count()) + " and " + std::to_string(spec_.out_c));
  weight_.write(weight);
  bias_.write(bias);
}

// Measured on lavapipe (bench conv, bench train's LDI stages): the direct kernel against the
// GEMM's gathers of 9 taps per input value, for layers of 8 or more output channels; one channel
// of a group of 16 would waste the rest of it.
bool Conv2d::direct(uint32_t channels) const {
  return ctx_.caps().cpu_driver && spec_.ksize == 3 && spec_.stride == 1 && channels >= 8;
}

void Conv2d::record_direct(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t in_c, uint32_t out_c,
                           const Shape& s, bool flip, bool accumulate) const {
  const gpu::Buffer& wt = flip ? weight_tb_ : weight_t_;
  const DirectGeometry geo = direct_geometry(ctx_);
  WeightTPC tpc{spec_.in_c, spec_.out_c, in_c, pad_group(out_c, geo.group), flip ? 1u : 0u, 0, 0, 0};
  cmd.dispatch("nn/conv_weight_t", {{kWeightTBindW, weight_}, {kWeightTBindWT, wt}}, tpc,
               cmd.linear_groups(gpu::Commands::div_up(uint64_t(tpc.rows) * 9 * tpc.cols, kNnGroupSize)));
  DirectConvPC pc{};
  pc.in_c = in_c, pc.out_c = out_c, pc.h = s.h, pc.w = s.w, pc.out_pad = tpc.cols;
  pc.blocks_x = gpu::Commands::div_up(s.w, 4), pc.blocks_y = gpu::Commands::div_up(s.h, geo.rows);
  pc.groups = pc.out_pad / geo.group, pc.images = s.n;
  pc.bias = flip ? 0u : 1u, pc.accumulate = accumulate ? 1u : 0u;
  const uint64_t blocks = uint64_t(pc.blocks_x) * pc.blocks_y * pc.groups * pc.images;
  cmd.dispatch(direct_kernel(ctx_, "conv3x3_direct", s.w),
               {{kDirectBindX, x.buffer()}, {kDirectBindWT, wt}, {kDirectBindBias, bias_}, {kDirectBindY, y.buffer()}},
               pc, cmd.linear_groups(gpu::Commands::div_up(blocks, kDirectGroupSize)));
}

void Conv2d::forward(gpu::Commands& cmd, const Tensor& x, const Tensor& y, uint32_t images) const {
  const Shape in = run_shape(x, images), out = output_shape(in);
  if (y.shape().image() != out.image() || y.shape().n < in.n)
    throw std::invalid_argument("conv " + name_ + " output: " + y.name() + " is " + y.shape().str() + ", expected " +
                                out.str());
  if (direct(spec_.out_c)) return record_direct(cmd, x, y, spec_.in_c, spec_.out_c, in, false, false);
  const uint32_t taps = spec_.ksize * spec_.ksize;
  ConvPC pc = conv_pc(spec_, in, out, spec_.out_c, uint32_t(out.count() / out.c), spec_.in_c * taps);
  cmd.dispatch(
      kernel("conv_fwd", pc.gemm_m),
      {{kConvFwdBindX, x.buffer()}, {kConvFwdBindW, weight_}, {kConvFwdBindBias, bias_}, {kConvFwdBindY, y.buffer()}},
      pc, tile_groups(cmd, pc));
}

void Conv2d::backward(gpu::Commands& cmd, const Tensor& x, const Tensor& dy, const Tensor* dx, bool accumulate_input,
                      bool accumulate_params, uint32_t images) {
  const Shape in = run_shape(x, images), out = output_shape(in);
  if (dy.shape().image() != out.image() || dy.shape().n < in.n)
    throw std::invalid_argument("conv " + name_ + " output gradient: " + dy.name() + " is " + dy.shape().str() +
                                ", expected " + out.str());
  if (dx) {
    if (dx->shape().image() != in.image() || dx->shape().n < in.n)
      throw std::invalid_argument("conv " + name_ + " input gradient: " + dx->name() + " is " + dx->shape().str() +
                                  ", expected " + in.str());
    if (direct(spec_.in_c)) {
      record_direct(cmd, dy, *dx, spec_.out_c, spec_.in_c, in, true, accumulate_input);
    } else {
      const uint32_t taps = spec_.ksize * spec_.ksize;
      ConvPC pc = conv_pc(spec_, in, out, spec_.in_c, uint32_t(in.count() / in.c), spec_.out_c * taps);
      pc.accumulate = accumulate_input ? 1u : 0u;
      cmd.dispatch(
          kernel("conv_bwd_input", pc.gemm_m),
          {{kConvBwdInputBindDy, dy.buffer()}, {kConvBwdInputBindW, weight_}, {kConvBwdInputBindDx, dx->buffer()}}, pc,
          tile_groups(cmd, pc));
    }
  }
  backward_weights(cmd, in, x, dy, accumulate_params);
}

// Partial sums per chunk of output pixels (m = out_c, n = weights per output channel + the bias
// column, k = output pixels of every image), then their sums in split order.
void Conv2d::backward_weights(gpu::Commands& cmd, const Shape& in, const Tensor& x, const Tensor& dy, bool accumulate) {
  const Shape out = output_shape(in);
  const uint32_t n = spec_.in_c * spec_.ksize * spec_.ksize + 1, pixels = uint32_t(out.count() / out.c);
  ConvPC pc = conv_pc(spec_, in, out, spec_.out_c, n, pixels);
  uint32_t per_split = 0;
  const uint64_t bytes = partial_bytes(in, &per_split);
  partial_.ensure(bytes);
  if (direct(spec_.out_c)) {
    const DirectGeometry geo = direct_geometry(ctx_);
    DirectGradPC dp{};
    dp.in_c = spec_.in_c, dp.out_c = spec_.out_c, dp.h = in.h, dp.w = in.w;
    dp.blocks_x = gpu::Commands::div_up(in.w, 4), dp.blocks_y = gpu::Commands::div_up(in.h, geo.rows);
    dp.groups = pad_group(spec_.out_c, geo.group) / geo.group, dp.images = in.n, dp.blocks_per_split = per_split;
    dp.splits = gpu::Commands::div_up(dp.blocks_x * dp.blocks_y * in.n, per_split);
    pc.splits = dp.splits;
    cmd.dispatch(direct_kernel(ctx_, "conv3x3_direct_dw", in.w),
                 {{kDirectDwBindX, x.buffer()},
                  {kDirectDwBindDy, dy.buffer()},
                  {kDirectDwBindPartial, gpu::BufferRef(partial_, 0, bytes)}},
                 dp,
                 cmd.linear_groups(gpu::Commands::div_up(uint64_t(dp.splits) * dp.groups * dp.in_c, kDirectGroupSize)));
  } else {
    pc.pixels_per_split = per_split;
    pc.splits = gpu::Commands::div_up(pixels, per_split);
    if (pc.splits > ctx_.caps().max_workgroup_count[2])
      throw gpu::Error("conv " + name_ + ": " + std::to_string(pc.splits) + " pixel splits exceed the device grid");
    gpu::Groups g = tile_groups(cmd, pc);
    g.z = pc.splits;
    cmd.dispatch(kernel("conv_bwd_weight", pc.gemm_m),
                 {{kConvBwdWeightBindX, x.buffer()},
                  {kConvBwdWeightBindDy, dy.buffer()},
                  {kConvBwdWeightBindPartial, gpu::BufferRef(partial_, 0, bytes)}},
                 pc, g);
  }
  pc.accumulate = accumulate ? 1u : 0u;
  cmd.dispatch("nn/conv_reduce",
               {{kConvReduceBindPartial, gpu::BufferRef(partial_, 0, bytes)},
                {kConvReduceBindDw, weight_grad_},
                {kConvReduceBindDb, bias_grad_}},
               pc, cmd.linear_groups(gpu::Commands::div_up(uint64_t(pc.gemm_m) * n, kReduceGroupSize)));
}

void Conv2d::add_to(Adam& adam, float lr) const {
  adam.add_group({name_ + ".weight", &weight_, &weight_grad_, uint32_t(weight_count()), lr, 1});
  adam.add_group({name_ + ".bias", &bias_, &bias_grad_, spec_.out_c, lr, 1});
}

}  // namespace evflow::nn
