#include "loss/loss_term.h"

#include <stdexcept>

namespace evflow {

LossTerm::LossTerm(gpu::Context& ctx, std::string name, float weight, uint32_t value_count)
    : ctx_(ctx),
      name_(std::move(name)),
      weight_(weight),
      value_count_(value_count),
      own_values_(ctx, uint64_t(value_count) * 4, name_ + "_values"),
      value_buffer_(&own_values_) {}

void LossTerm::set_value_slot(const gpu::Buffer& buffer, uint32_t first) {
  if (buffer.size() < (uint64_t(first) + value_count_) * 4)
    throw std::invalid_argument("loss " + name_ + ": value slot past the end of " + buffer.name());
  value_buffer_ = &buffer;
  value_first_ = first;
}

double LossTerm::value() const { return value_buffer_->read_one<float>(value_first_); }

std::vector<float> LossTerm::values() const {
  return value_buffer_->read<float>(value_count_, uint64_t(value_first_) * 4);
}

}  // namespace evflow
