// Trainer kernels: push constants shared by engine/train and shaders/train.
#ifndef EVF_TRAIN_LAYOUT_H
#define EVF_TRAIN_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN
EVF_CONST(uint, kAccumulateGroupSize, 256u)  // each invocation: four elements
struct AccumulatePC {
  uint n;
  float scale;
  uint accumulate;  // 0: y = scale * x; 1: y += scale * x
  uint pad;
};
// Colour conversions of the image model (train/colour.comp, one build per op: train/colour_<op>):
// bindings, ops (each invocation converts four elements).
EVF_CONST(uint, kColourGroupSize, 256u)
EVF_BIND(kColourBindX, 0u, X)
EVF_BIND(kColourBindG, 1u, G)
EVF_BIND(kColourBindY, 2u, Y)
EVF_BIND(kColourBindMean, 3u, Mean)  // train/colour_decode_mean: the frames' mean, added to
EVF_BIND(kColourBindMeanIn, 4u, MeanIn)  // train/colour_decode_mean: a texel view of Mean, read
EVF_CONST(uint, kColourDecode, 0u)
EVF_CONST(uint, kColourEncode, 1u)
EVF_CONST(uint, kColourDecodeBwd, 2u)
EVF_CONST(uint, kColourEncodeBwd, 3u)
struct ColourPC {
  uint n;
  float scale;      // train/colour_decode_mean: Mean = (accumulate ? Mean : 0) + scale * y
  uint accumulate;
  uint pad0;
};
// Every frame of an exposure of F = 2..kDecodeMeanMaxFrames frames decoded and averaged in one
// pass (train/decode_mean_f<F>, ColourPC without `accumulate`): Y_k = decode(X_k) and Mean =
// sum over k, in frame order, of scale * Y_k. X_k texels, Y_k and Mean storage.
EVF_CONST(uint, kDecodeMeanMaxFrames, 9u)
EVF_BIND(kDecodeMeanBindMean, 0u, Mean)
EVF_BIND(kDecodeMeanBindX0, 1u, X0)
EVF_BIND(kDecodeMeanBindX1, 2u, X1)
EVF_BIND(kDecodeMeanBindX2, 3u, X2)
EVF_BIND(kDecodeMeanBindX3, 4u, X3)
EVF_BIND(kDecodeMeanBindX4, 5u, X4)
EVF_BIND(kDecodeMeanBindX5, 6u, X5)
EVF_BIND(kDecodeMeanBindX6, 7u, X6)
EVF_BIND(kDecodeMeanBindX7, 8u, X7)
EVF_BIND(kDecodeMeanBindX8, 9u, X8)
EVF_BIND(kDecodeMeanBindY0, 10u, Y0)
EVF_BIND(kDecodeMeanBindY1, 11u, Y1)
EVF_BIND(kDecodeMeanBindY2, 12u, Y2)
EVF_BIND(kDecodeMeanBindY3, 13u, Y3)
EVF_BIND(kDecodeMeanBindY4, 14u, Y4)
EVF_BIND(kDecodeMeanBindY5, 15u, Y5)
EVF_BIND(kDecodeMeanBindY6, 16u, Y6)
EVF_BIND(kDecodeMeanBindY7, 17u, Y7)
EVF_BIND(kDecodeMeanBindY8, 18u, Y8)

// Flow-upsampled blur (train/upsample, train/upsample_bwd; engine/train/image_model.h). For
// interval i of the exposure, its displacement planes dx, dy (H*W each, at flow[2 i H W]) and
// sub-frames m = 1..upsample-1 at s = m / upsample:
//   S_m(L)(x) = sum over the included taps q of w_q L(q) / sum of their w_q,
//   taps: the bilinear taps of x - s d(x); tap q is included when
//   max(|x - (q + roundEven(s d(q)))|) <= kUpsampleReach (so the adjoint is a gather over that
//   square), else no tap: S_m(L)(x) = L(x).
// upsample_taps: each target's taps for every m of interval i, kUpsampleTapFloats floats per
//               (m, x) at taps[((i (M - 1) + m - 1) H W + x) * kUpsampleTapFloats]: the top-left
//               tap's x and y (int bits) and the four normalised weights (all 0: no tap)
// upsample:     y[c][x] += scale * sum_m S_m(L)[c][x]
// upsample_bwd: y[c][q] = g[c][q] + sum_m S_m^T(g)[c][q]   (frame i's share of the mean's gradient)
EVF_CONST(uint, kUpsampleGroupSize, 64u)
EVF_CONST(int, kUpsampleReach, 2)
EVF_CONST(uint, kUpsampleTapFloats, 6u)
struct UpsamplePC {
  uint width;
  uint height;
  uint interval;
  uint upsample;  // M
  float scale;
  uint pad0, pad1, pad2;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// train/accumulate
EVF_BIND(kTrainAccumulateBindX, 0u, X)
EVF_BIND(kTrainAccumulateBindY, 1u, Y)
// train/upsample_taps
EVF_BIND(kUpsampleTapsBindFlow, 0u, Flow)
EVF_BIND(kUpsampleTapsBindTaps, 1u, Taps)
// train/upsample
EVF_BIND(kUpsampleBindTaps, 0u, Taps)
EVF_BIND(kUpsampleBindFrame, 1u, Frame)
EVF_BIND(kUpsampleBindMean, 2u, Mean)
// train/upsample_bwd
EVF_BIND(kUpsampleBwdBindFlow, 0u, Flow)
EVF_BIND(kUpsampleBwdBindTaps, 1u, Taps)
EVF_BIND(kUpsampleBwdBindGrad, 2u, Grad)
EVF_BIND(kUpsampleBwdBindShare, 3u, Share)

#ifdef __cplusplus
// Frame k's bindings of train/decode_mean_f<F>, by k.
inline constexpr BindSlot kDecodeMeanBindXs[] = {kDecodeMeanBindX0, kDecodeMeanBindX1, kDecodeMeanBindX2,
                                                 kDecodeMeanBindX3, kDecodeMeanBindX4, kDecodeMeanBindX5,
                                                 kDecodeMeanBindX6, kDecodeMeanBindX7, kDecodeMeanBindX8};
inline constexpr BindSlot kDecodeMeanBindYs[] = {kDecodeMeanBindY0, kDecodeMeanBindY1, kDecodeMeanBindY2,
                                                 kDecodeMeanBindY3, kDecodeMeanBindY4, kDecodeMeanBindY5,
                                                 kDecodeMeanBindY6, kDecodeMeanBindY7, kDecodeMeanBindY8};
static_assert(sizeof(kDecodeMeanBindXs) / sizeof(BindSlot) == kDecodeMeanMaxFrames);
#endif

EVF_NAMESPACE_END
#endif
