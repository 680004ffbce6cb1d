// Trainer kernels: push constants shared by engine/train and shaders/train.
#ifndef EVF_TRAIN_LAYOUT_H
#define EVF_TRAIN_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kAccumulateGroupSize, 256u)
struct AccumulatePC {
  uint n;
  float scale;
  uint accumulate;  // 0: y = scale * x; 1: y += scale * x
  uint pad;
};
EVF_NAMESPACE_END
#endif
