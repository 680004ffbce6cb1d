#include "loss/event_sums.h"

#include "loss/loss_layout.h"

namespace evflow {

namespace {

// loss/reduce with out[dst + c * n_out + j] = component j of column c's sum, a workgroup a column.
void record_components(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                       uint32_t dst, uint32_t n_out, uint32_t columns) {
  shaderio::ReducePC r{};
  r.coeff0 = glm::vec4(1, 0, 0, 0);
  r.coeff1 = glm::vec4(0, 1, 0, 0);
  r.coeff2 = glm::vec4(0, 0, 1, 0);
  r.coeff3 = glm::vec4(0, 0, 0, 1);
  r.n_partials = n_partials;
  r.dst = dst;
  r.n_out = n_out;
  cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials}, {shaderio::kReduceBindOut, sums}}, r,
               gpu::Groups{columns, 1, 1});
}

}  // namespace

void record_event_sums(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                       uint32_t dst) {
  record_components(cmd, partials, sums, n_partials, dst, 3, 1);
}

void record_event_columns(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                          uint32_t columns) {
  record_components(cmd, partials, sums, n_partials, 0, 4, columns);
}

}  // namespace evflow
