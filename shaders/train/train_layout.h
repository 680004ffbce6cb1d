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
// Colour conversions of the image model (train/colour.comp): bindings, ops.
EVF_CONST(uint, kColourGroupSize, 256u)
EVF_BIND(kColourBindX, 0u, X)
EVF_BIND(kColourBindG, 1u, G)
EVF_BIND(kColourBindY, 2u, Y)
EVF_CONST(uint, kColourDecode, 0u)
EVF_CONST(uint, kColourEncode, 1u)
EVF_CONST(uint, kColourDecodeBwd, 2u)
EVF_CONST(uint, kColourEncodeBwd, 3u)
struct ColourPC {
  uint n;
  uint op;
  uint pad0, pad1;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// train/accumulate
EVF_BIND(kTrainAccumulateBindX, 0u, X)
EVF_BIND(kTrainAccumulateBindY, 1u, Y)

EVF_NAMESPACE_END
#endif
