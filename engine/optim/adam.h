// Adam on the GPU over parameter groups (3DGS style: one learning rate per group), one dispatch
// per group per step. The optimizer owns the two moment buffers of every group and zeroes them
// itself (on the first command recorded for the group); gradients are read, never cleared.
//
// Rows: a group is `count` floats seen as count / row_width rows (one Gaussian = one row: 3
// floats for means, 48 for SH, ...). Density control works on rows: reset_rows / reset_masked
// zero the moments of selected rows, gather() reorders / compacts / grows all state by an index
// buffer (new row r = old row index[r], or zero for kAdamNoSource) so that the state follows
// cloned and pruned Gaussians; gather_rows() does the same for any float buffer (parameters).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "gpu/commands.h"

namespace evflow {

inline constexpr uint32_t kAdamNoSource = 0xFFFFFFFFu;

struct AdamGroup {
  std::string name;
  const gpu::Buffer* param = nullptr;  // updated in place; at least count floats
  const gpu::Buffer* grad = nullptr;   // read; at least count floats
  uint32_t count = 0;                  // floats
  float lr = 1e-3f;
  uint32_t row_width = 1;  // floats per row; count must be a multiple
};

struct AdamOptions {
  double beta1 = 0.9;  // double: 1 - beta is formed on the host before rounding to float
  double beta2 = 0.999;
  double eps = 1e-15;
};

class Adam {
 public:
  explicit Adam(gpu::Context& ctx, AdamOptions opts = {});

  // Returns the group's index. Moments are allocated here and zeroed on first use.
  size_t add_group(const AdamGroup& group);
  size_t group_count() const { return groups_.size(); }
  size_t group_index(const std::string& name) const;  // throws when absent
  const AdamGroup& group(size_t i) const { return groups_.at(i)->desc; }

  void set_lr(size_t i, float lr) { groups_.at(i)->desc.lr = lr; }
  float lr(size_t i) const { return groups_.at(i)->desc.lr; }
  // Points a group at other parameter/gradient buffers (after the owner reallocated them).
  void set_buffers(size_t i, const gpu::Buffer& param, const gpu::Buffer& grad);
  // Steps taken by the group (bias correction uses step_count + 1 for the next step).
  uint64_t step_count(size_t i) const { return groups_.at(i)->step; }
  const AdamOptions& options() const { return opts_; }

  // One Adam step of every group (one dispatch each), or of one group.
  void step(gpu::Commands& cmd);
  void step_group(gpu::Commands& cmd, size_t i);
  // A step of group i whose gradient the caller knows to be exactly zero. While the group's
  // moments are zero too (it has never stepped with a gradient nor loaded a state), Adam's update
  // is zero and leaves both moments at zero: the step is only counted, with no dispatch. Otherwise
  // an ordinary step.
  void step_group_zero_grad(gpu::Commands& cmd, size_t i);

  // Zero both moments of rows rows[0..n) (an index list; out-of-range rows are ignored).
  void reset_rows(gpu::Commands& cmd, size_t i, const gpu::Buffer& rows, uint32_t n);
  // Zero both moments of every row r with mask[r] != 0 (mask: one uint per current row).
  void reset_masked(gpu::Commands& cmd, size_t i, const gpu::Buffer& mask);
  // new row r = old row index[r] for r < new_rows (kAdamNoSource: zero), for both moments. The
  // group's count becomes new_rows * row_width (its param/grad buffers must then hold that many).
  // At most one gather per group between two submits (it may reallocate the spare moments).
  void gather(gpu::Commands& cmd, size_t i, const gpu::Buffer& index, uint32_t new_rows);
  // dst[r * width + k] = src[index[r] * width + k] (kAdamNoSource: 0) for r < rows, k < width.
  static void gather_rows(gpu::Commands& cmd, const gpu::Buffer& src, const gpu::Buffer& dst, const gpu::Buffer& index,
                          uint32_t rows, uint32_t width);

  // Restores a group's state (from a checkpoint): both moments (count floats each) and the
  // step count. Throws when the sizes differ from the group's count.
  void load_state(size_t i, const std::vector<float>& exp_avg, const std::vector<float>& exp_avg_sq, uint64_t step);
  // Moments of a group (first `count` floats are meaningful).
  const gpu::Buffer& exp_avg(size_t i) const { return *groups_.at(i)->m; }
  const gpu::Buffer& exp_avg_sq(size_t i) const { return *groups_.at(i)->v; }

 private:
  struct State {
    AdamGroup desc;
    uint64_t step = 0;
    bool zeroed = false;
    bool moments_zero = true;  // no step with a gradient and no loaded state yet
    // Two pairs of moment buffers: gather writes the spare pair, then they swap.
    gpu::Buffer buf[4];
    gpu::Buffer* m = nullptr;
    gpu::Buffer* v = nullptr;
  };
  void prepare(gpu::Commands& cmd, State& s);
  gpu::Context& ctx_;
  AdamOptions opts_;
  std::vector<std::unique_ptr<State>> groups_;
};

}  // namespace evflow
