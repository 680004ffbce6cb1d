// Optimizer: push constants and sizes shared by engine/optim (C++) and shaders/optim (GLSL).
#ifndef EVF_OPTIM_LAYOUT_H
#define EVF_OPTIM_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kOptimGroupSize, 256u)
EVF_CONST(uint, kOptimNoSource, 0xFFFFFFFFu)  // gather: index value meaning "zero state"

// optim/adam, one invocation per four elements (PyTorch's formulation):
//   m = b1 m + (1 - b1) g;  v = b2 v + (1 - b2) g^2
//   p -= step_size * m / (sqrt(v) * inv_sqrt_bc2 + eps)
// with step_size = lr / (1 - b1^t) and inv_sqrt_bc2 = 1 / sqrt(1 - b2^t) for step t (1-based),
// and 1 - b1, 1 - b2, all computed on the host in double (1 - 0.999f in float is off by 1e-5).
struct AdamPC {
  uint count;
  float beta1;
  float beta2;
  float eps;
  float one_minus_beta1;
  float one_minus_beta2;
  float step_size;
  float inv_sqrt_bc2;
};

// optim/gather: dst[r * width + k] = index[r] == kOptimNoSource ? 0 : src[index[r] * width + k]
// for r < rows, k < width.
// optim/reset: zero m and v of selected rows: mode 0: rows r < rows with select[r] != 0 (a mask),
// mode 1: rows select[i] for i < rows (an index list; rows >= total_rows are skipped).
struct RowsPC {
  uint rows;
  uint width;
  uint mode;
  uint total_rows;  // reset: rows in the moment buffers
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// optim/adam
EVF_BIND(kAdamBindParam, 0u, Param)
EVF_BIND(kAdamBindGrad, 1u, Grad)
EVF_BIND(kAdamBindM, 2u, M)
EVF_BIND(kAdamBindV, 3u, V)
// Texel views of Param, M and V (the same buffers) for the values each element's update reads.
EVF_BIND(kAdamBindParamIn, 4u, ParamIn)
EVF_BIND(kAdamBindMIn, 5u, MIn)
EVF_BIND(kAdamBindVIn, 6u, VIn)
// optim/gather
EVF_BIND(kOptimGatherBindSrc, 0u, Src)
EVF_BIND(kOptimGatherBindDst, 1u, Dst)
EVF_BIND(kOptimGatherBindIndex, 2u, Index)
// optim/reset
EVF_BIND(kOptimResetBindM, 0u, M)
EVF_BIND(kOptimResetBindV, 1u, V)
EVF_BIND(kOptimResetBindSelect, 2u, Select)

EVF_NAMESPACE_END
#endif
