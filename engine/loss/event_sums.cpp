#include "loss/event_sums.h"

#include "loss/loss_layout.h"

namespace evflow {

void record_event_sums(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                       uint32_t dst) {
  shaderio::ReducePC r{};
  r.coeff0 = glm::vec4(1, 0, 0, 0);
  r.coeff1 = glm::vec4(0, 1, 0, 0);
  r.coeff2 = glm::vec4(0, 0, 1, 0);
  r.n_partials = n_partials;
  r.dst = dst;
  r.n_out = 3;
  cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials}, {shaderio::kReduceBindOut, sums}}, r,
               gpu::Groups{1, 1, 1});
}

void record_event_columns(gpu::Commands& cmd, const gpu::Buffer& partials, const gpu::Buffer& sums, uint32_t n_partials,
                          uint32_t columns) {
  shaderio::ReducePC r{};
  r.coeff0 = glm::vec4(1, 0, 0, 0);
  r.coeff1 = glm::vec4(0, 1, 0, 0);
  r.coeff2 = glm::vec4(0, 0, 1, 0);
  r.coeff3 = glm::vec4(0, 0, 0, 1);
  r.n_partials = n_partials;
  r.n_out = 4;
  cmd.dispatch("loss/reduce", {{shaderio::kReduceBindPartials, partials}, {shaderio::kReduceBindOut, sums}}, r,
               gpu::Groups{columns, 1, 1});
}

}  // namespace evflow
