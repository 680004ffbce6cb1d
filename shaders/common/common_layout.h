// Kernels of shaders/common: sizes and bindings shared with their C++ callers.
#ifndef EVF_COMMON_LAYOUT_H
#define EVF_COMMON_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

// common/iota: values[i] = i + offset.
EVF_CONST(uint, kIotaGroupSize, 64u)
EVF_BIND(kIotaBindValues, 0u, Values)

EVF_NAMESPACE_END
#endif
