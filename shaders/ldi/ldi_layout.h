// The learnable double integral (LDI): push constants, workgroup sizes and bindings shared by
// engine/ldi (C++) and shaders/ldi (GLSL).
//
// Event tensors. The LDI's input for one side of a frame time t_i is kLdiBins time bins x 2
// polarities of the events of that side, channel 2 * bin + polarity (polarity 0: positive after
// the side's flip), crop_h x crop_w pixels. The host turns the bins' time edges into index ranges
// of the packed events (events/events_layout.h): bound[k] <= e < bound[k + 1] is index-order
// interval k, k < bins. With `reversed` (the side before t_i) interval k is time bin
// bins - 1 - k and the polarities swap.
#ifndef EVF_LDI_LAYOUT_H
#define EVF_LDI_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kLdiBins, 16u)
EVF_CONST(uint, kLdiChannels, 32u)  // kLdiBins x 2 polarities
EVF_CONST(uint, kLdiBoundVecs, 5u)  // uvec4s holding the kLdiBins + 1 bounds
EVF_CONST(uint, kLdiGroupSize, 256u)

// ldi/bin_events: for each event e in [bound[0], bound[bins]) inside the crop,
//   counts[((channel_base + 2 bin + pol) crop_h + y - crop_y) crop_w + x - crop_x] += 1
// (uint atomics: exact, order-independent). With bins = 1 and channel_base = 2 plane this is a
// plane of the event loss's counts ([positive H*W][negative H*W]) over the crop.
struct LdiBinPC {
  uvec4 bound[kLdiBoundVecs];
  uint bins;
  uint reversed;
  uint channel_base;
  uint crop_x;
  uint crop_y;
  uint crop_w;
  uint crop_h;
  uint pad0;
};

// ldi/counts_to_float: v[i] = float(v[i]) in place (uint counts -> the network's float input).
struct LdiCountPC {
  uint n;
  uint pad0, pad1, pad2;
};

// ldi/crop: out[c][y][x] = full[c][crop_y + y][crop_x + x];
// ldi/uncrop_add: full[c][crop_y + y][crop_x + x] += out[c][y][x]; for c < channels.
struct LdiCropPC {
  uint channels;
  uint width;  // of the full image
  uint height;
  uint crop_x;
  uint crop_y;
  uint crop_w;
  uint crop_h;
  uint pad0;
};

// The double integral of frame i (ldi_math.glsl), per crop pixel p, from the two sides' network
// outputs a = LDI(P(E[t_i, t_0])) and b = LDI(P(E[t_i, t_2N])) (planes `before` and `after` of
// `sides`, one plane per network call; kLdiNoSide for a side that was not run, whose weight is 0):
//   x = w1 a + w2 b,  E = softplus(x) + kLdiFloor,  C[c] = B[c] / E  (B: the blurry crop, linear).
// ldi/combine writes E (plane i of `integral`) and C (frame i's own 3-plane buffer).
// ldi/combine_bwd writes d/da and d/db (planes `before`, `after` of `side_grads`) from `grads`:
//   mode kLdiFromFrames: d/dC (frame i's own 3-plane buffer), scaled by `scale`, plus, where
//                        `anchor` is not 0, anchor * d/dE of the regression below to plane i
//                        of `Anchor` (the anchor to EDI's integral in training);
//   mode kLdiFromTarget: the regression (log E - log D)^2 to the target D (plane i), scaled by
//                        `scale` (1 / the number of regressed values).
EVF_CONST(float, kLdiFloor, 1e-3)
EVF_CONST(uint, kLdiFromFrames, 0u)
EVF_CONST(uint, kLdiFromTarget, 1u)
EVF_CONST(uint, kLdiNoSide, 0xffffffffu)
struct LdiCombinePC {
  uint pixels;  // crop_w * crop_h
  uint frame;   // i
  float w1;
  float w2;
  uint mode;
  float scale;
  uint before;  // planes of the sides (network calls), or kLdiNoSide
  uint after;
  float anchor;
  uint pad0, pad1, pad2;
};

// ldi/mean_values: values[dst] = scale * sum over k < count of src[first + k * stride] (the mean
// of a term's per-frame values, in a fixed order).
struct LdiMeanPC {
  uint count;
  uint stride;
  uint first;
  uint dst;
  float scale;
  uint pad0, pad1, pad2;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// ldi/bin_events
EVF_BIND(kLdiBinBindPacked, 0u, Packed)
EVF_BIND(kLdiBinBindCounts, 1u, Counts)
// ldi/counts_to_float
EVF_BIND(kLdiCountBindValues, 0u, Values)
// ldi/crop, ldi/uncrop_add
EVF_BIND(kLdiCropBindFull, 0u, Full)
EVF_BIND(kLdiCropBindOut, 1u, Out)
// ldi/combine
EVF_BIND(kLdiCombineBindSides, 0u, Sides)
EVF_BIND(kLdiCombineBindBlurry, 1u, Blurry)
EVF_BIND(kLdiCombineBindIntegral, 2u, Integral)
EVF_BIND(kLdiCombineBindFrames, 3u, Frames)
// ldi/combine_bwd (kLdiFromFrames binds FrameGrads, kLdiFromTarget binds Target: the same slot)
EVF_BIND(kLdiCombineBwdBindSides, 0u, Sides)
EVF_BIND(kLdiCombineBwdBindBlurry, 1u, Blurry)
EVF_BIND(kLdiCombineBwdBindGrads, 2u, Grads)
EVF_BIND(kLdiCombineBwdBindSideGrads, 3u, SideGrads)
EVF_BIND(kLdiCombineBwdBindAnchor, 4u, Anchor)
// ldi/mean_values
EVF_BIND(kLdiMeanBindSrc, 0u, Src)
EVF_BIND(kLdiMeanBindValues, 1u, Values)

EVF_NAMESPACE_END
#endif
