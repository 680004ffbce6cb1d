#include "optim/adam.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "optim/optim_layout.h"

namespace evflow {

using shaderio::kOptimGroupSize;
static_assert(kAdamNoSource == shaderio::kOptimNoSource);

namespace {
void check_floats(const gpu::Buffer* b, uint64_t count, const std::string& what) {
  if (!b || !b->valid()) throw std::invalid_argument("adam: " + what + " buffer missing");
  if (b->size() < count * 4)
    throw std::invalid_argument("adam: " + what + " buffer " + b->name() + " holds " + std::to_string(b->size()) +
                                " bytes, needs " + std::to_string(count * 4));
}
}  // namespace

Adam::Adam(gpu::Context& ctx, AdamOptions opts) : ctx_(ctx), opts_(opts) {}

size_t Adam::add_group(const AdamGroup& g) {
  if (g.row_width == 0 || g.count % g.row_width)
    throw std::invalid_argument("adam: group " + g.name + ": count not a multiple of row_width");
  for (auto& s : groups_)
    if (s->desc.name == g.name) throw std::invalid_argument("adam: duplicate group " + g.name);
  auto s = std::make_unique<State>();
  s->desc = g;
  const uint64_t bytes = std::max<uint64_t>(uint64_t(g.count) * 4, 16);
  for (int k = 0; k < 4; ++k)
    s->buf[k] = gpu::Buffer(ctx_, k < 2 ? bytes : 16, "adam_" + g.name + (k % 2 ? "_v" : "_m"));
  s->m = &s->buf[0];
  s->v = &s->buf[1];
  groups_.push_back(std::move(s));
  return groups_.size() - 1;
}

size_t Adam::group_index(const std::string& name) const {
  for (size_t i = 0; i < groups_.size(); ++i)
    if (groups_[i]->desc.name == name) return i;
  throw std::out_of_range("adam: no group " + name);
}

void Adam::set_buffers(size_t i, const gpu::Buffer& param, const gpu::Buffer& grad) {
  auto& d = groups_.at(i)->desc;
  d.param = &param;
  d.grad = &grad;
}

void Adam::load_state(size_t i, const std::vector<float>& m, const std::vector<float>& v, uint64_t step) {
  State& s = *groups_.at(i);
  if (m.size() != s.desc.count || v.size() != s.desc.count)
    throw std::invalid_argument("adam: group " + s.desc.name + ": state of " + std::to_string(m.size()) + "/" +
                                std::to_string(v.size()) + " values for a group of " + std::to_string(s.desc.count));
  s.m->write(m);
  s.v->write(v);
  s.step = step;
  s.zeroed = true;
  s.moments_zero = false;
}

void Adam::prepare(gpu::Commands& cmd, State& s) {
  if (s.zeroed) return;
  cmd.fill(*s.m, 0u);
  cmd.fill(*s.v, 0u);
  s.zeroed = true;
}

void Adam::step(gpu::Commands& cmd) {
  for (size_t i = 0; i < groups_.size(); ++i) step_group(cmd, i);
}

void Adam::step_group(gpu::Commands& cmd, size_t i) {
  State& s = *groups_.at(i);
  const AdamGroup& g = s.desc;
  check_floats(g.param, g.count, g.name + " param");
  check_floats(g.grad, g.count, g.name + " grad");
  prepare(cmd, s);
  s.step += 1;
  if (g.count == 0) return;
  s.moments_zero = false;
  const double t = double(s.step);
  const double bc1 = 1.0 - std::pow(opts_.beta1, t);
  const double bc2 = 1.0 - std::pow(opts_.beta2, t);
  shaderio::AdamPC pc{};
  pc.count = g.count;
  pc.beta1 = static_cast<float>(opts_.beta1);
  pc.beta2 = static_cast<float>(opts_.beta2);
  pc.eps = static_cast<float>(opts_.eps);
  pc.one_minus_beta1 = static_cast<float>(1.0 - opts_.beta1);
  pc.one_minus_beta2 = static_cast<float>(1.0 - opts_.beta2);
  pc.step_size = static_cast<float>(double(g.lr) / bc1);
  pc.inv_sqrt_bc2 = static_cast<float>(1.0 / std::sqrt(bc2));
  cmd.dispatch("optim/adam",
               {{shaderio::kAdamBindParam, *g.param},
                {shaderio::kAdamBindGrad, *g.grad},
                {shaderio::kAdamBindM, *s.m},
                {shaderio::kAdamBindV, *s.v},
                {shaderio::kAdamBindParamIn, *g.param},
                {shaderio::kAdamBindMIn, *s.m},
                {shaderio::kAdamBindVIn, *s.v}},
               pc, cmd.linear_groups(gpu::Commands::div_up(gpu::Commands::div_up(g.count, 4), kOptimGroupSize)));
}

void Adam::step_group_zero_grad(gpu::Commands& cmd, size_t i) {
  State& s = *groups_.at(i);
  if (!s.moments_zero) return step_group(cmd, i);
  prepare(cmd, s);
  s.step += 1;  // m = v = 0 stay 0, and the parameters move by 0 / (0 + eps)
}

void Adam::reset_rows(gpu::Commands& cmd, size_t i, const gpu::Buffer& rows, uint32_t n) {
  State& s = *groups_.at(i);
  prepare(cmd, s);
  if (n == 0) return;
  check_floats(&rows, n, s.desc.name + " reset rows");
  shaderio::RowsPC pc{n, s.desc.row_width, 1u, s.desc.count / s.desc.row_width};
  cmd.dispatch(
      "optim/reset",
      {{shaderio::kOptimResetBindM, *s.m}, {shaderio::kOptimResetBindV, *s.v}, {shaderio::kOptimResetBindSelect, rows}},
      pc, cmd.linear_groups(gpu::Commands::div_up(uint64_t(n) * s.desc.row_width, kOptimGroupSize)));
}

void Adam::reset_masked(gpu::Commands& cmd, size_t i, const gpu::Buffer& mask) {
  State& s = *groups_.at(i);
  prepare(cmd, s);
  const uint32_t rows = s.desc.count / s.desc.row_width;
  if (rows == 0) return;
  check_floats(&mask, rows, s.desc.name + " reset mask");
  shaderio::RowsPC pc{rows, s.desc.row_width, 0u, rows};
  cmd.dispatch(
      "optim/reset",
      {{shaderio::kOptimResetBindM, *s.m}, {shaderio::kOptimResetBindV, *s.v}, {shaderio::kOptimResetBindSelect, mask}},
      pc, cmd.linear_groups(gpu::Commands::div_up(s.desc.count, kOptimGroupSize)));
}

void Adam::gather_rows(gpu::Commands& cmd, const gpu::Buffer& src, const gpu::Buffer& dst, const gpu::Buffer& index,
                       uint32_t rows, uint32_t width) {
  if (rows == 0 || width == 0) return;
  check_floats(&dst, uint64_t(rows) * width, "gather dst");
  check_floats(&index, rows, "gather index");
  shaderio::RowsPC pc{rows, width, 0u, 0u};
  cmd.dispatch("optim/gather",
               {{shaderio::kOptimGatherBindSrc, src},
                {shaderio::kOptimGatherBindDst, dst},
                {shaderio::kOptimGatherBindIndex, index}},
               pc, cmd.linear_groups(gpu::Commands::div_up(uint64_t(rows) * width, kOptimGroupSize)));
}

void Adam::gather(gpu::Commands& cmd, size_t i, const gpu::Buffer& index, uint32_t new_rows) {
  State& s = *groups_.at(i);
  prepare(cmd, s);
  const uint32_t w = s.desc.row_width;
  const uint64_t new_count = uint64_t(new_rows) * w;
  if (new_count > 0xFFFFFFFFull) throw std::invalid_argument("adam: group " + s.desc.name + " too large");
  gpu::Buffer* spare_m = (s.m == &s.buf[0]) ? &s.buf[2] : &s.buf[0];
  gpu::Buffer* spare_v = (s.v == &s.buf[1]) ? &s.buf[3] : &s.buf[1];
  // ensure() may reallocate the spare pair: it must not be referenced by commands recorded but
  // not yet submitted (see adam.h: one gather per group between submits).
  spare_m->ensure(std::max<uint64_t>(new_count * 4, 16));
  spare_v->ensure(std::max<uint64_t>(new_count * 4, 16));
  gather_rows(cmd, *s.m, *spare_m, index, new_rows, w);
  gather_rows(cmd, *s.v, *spare_v, index, new_rows, w);
  s.m = spare_m;
  s.v = spare_v;
  s.desc.count = static_cast<uint32_t>(new_count);
}

}  // namespace evflow
