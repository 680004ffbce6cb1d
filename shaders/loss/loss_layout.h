// Image losses and metrics: push constants, flags and sizes shared by engine/loss (C++) and
// shaders/loss (GLSL).
//
// Images are planar float: img[c*H*W + y*W + x]. Every per-pixel kernel runs one invocation per
// element (linear index i = c*H*W + y*W + x) in workgroups of kLossGroupSize, and writes the
// workgroup's sum of its per-pixel values into partials[group] (a vec4, fixed-order tree in
// shared memory). loss/reduce then sums the partials in a fixed order (no atomics), so every
// value is bit-for-bit reproducible on a given device.
#ifndef EVF_LOSS_LAYOUT_H
#define EVF_LOSS_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kLossGroupSize, 256u)
EVF_CONST(uint, kReduceGroupSize, 256u)
EVF_CONST(uint, kReduceMaxOutputs, 4u)

// SSIM window: 11 x 11 Gaussian, sigma 1.5 (the separable 1D taps are in ssim_math.glsl).
EVF_CONST(int, kSsimRadius, 5)
EVF_CONST(uint, kSsimTaps, 11u)
// The SSIM passes run one invocation per strip of kSsimStrip pixels: horizontal passes a row
// segment (c, y, segment), vertical passes a column strip (c, strip, x), so that each loaded
// value serves up to 11 outputs (CPU drivers are bound by loads).
EVF_CONST(uint, kSsimStrip, 8u)

// Flags of the per-pixel kernels.
EVF_CONST(uint, kLossWriteGrad, 1u)     // write the gradient (else forward only)
EVF_CONST(uint, kLossAccumulate, 2u)    // grad += value (else grad = value; grad is not read)
EVF_CONST(uint, kLossPixelL2, 4u)       // per-pixel term (A-B)^2 instead of |A-B|
EVF_CONST(uint, kLossWriteSsimMap, 8u)  // ssim_v: store the per-pixel SSIM map in D (after its vec4s)

// loss/pixel: e_i = |A_i - B_i| (or (A_i - B_i)^2); partials[g].x = sum of e over the group;
// grad_i (+)= grad_scale * de_i/dA_i.
struct PixelPC {
  uint count;        // C*H*W
  uint flags;
  float grad_scale;  // weight / count for a mean
  uint pad0;
};

// loss/ssim_h, ssim_v, ssim_bwd_h, ssim_bwd_v.
//   H: count vec4s (horizontally filtered A, B, A^2 + B^2, AB of element i in H[i]); the backward
//      reuses H[i].xyz for the horizontally filtered partial derivatives
//   D: count vec4s (dS/dmu_A, dS/d(E[A^2 + B^2]), dS/d(E[AB]), 0 of element i in D[i]), then the SSIM
//      map (optional) as a plane of count floats (float 4 count + i)
//   Interleaved, a tap reads one vec4 where it would read four floats (CPU drivers: one lane loop).
// ssim_v partials[g] = (sum of the per-pixel term e, sum of SSIM, 0, 0).
// ssim_bwd_v: grad (+)= ssim_grad_scale * dSSIM_sum/dA + pixel_grad_scale * de/dA.
struct SsimPC {
  uint channels;
  uint height;
  uint width;
  uint count;             // channels * height * width
  uint flags;
  float c1;               // (0.01 L)^2
  float c2;               // (0.03 L)^2
  float ssim_grad_scale;
  float pixel_grad_scale;
  uint pad0, pad1, pad2;
};

// loss/reduce: s = sum over g < n_partials of partials[g] (vec4), in a fixed order; then for
// j < n_out: out[dst + j] = dot(coeff[j], s) + offset[j], and -10 log10(that) where bit j of
// log_mask is set (PSNR from MSE). Workgroup c of a dispatch of several does the same for column
// c: partials[c * n_partials + g] into out[dst + c * n_out + j].
struct ReducePC {
  vec4 coeff0;
  vec4 coeff1;
  vec4 coeff2;
  vec4 coeff3;
  vec4 offset;
  uint n_partials;
  uint dst;
  uint n_out;
  uint log_mask;
};

// Event loss (paper Eq. 5, engine/loss/event_loss.h). One record per pair (t_s, t_j), s < j:
// loss/event_pair: per cell of pool x pool pixels (one pixel at pool 1; cells cut by the border),
// the sums over the cell's pixels of
//   E = sum over interval planes [plane_first, plane_last] of theta_pos * n_pos - theta_neg * n_neg
//       (n: uint counts, or with counts_float the planes' float amounts)
//   D = L_j - L_s,  L = log(eps + max(0, luminance(rgb)))   (the later minus the earlier frame:
//       the sign of the events, checked against the simulator in tests/test_event_loss.cpp)
// writes E and D into scratch planes 0 and 1 (a value per cell) and partials[g] = (sum E*D,
// sum D*D, sum E*E, 0) over the group's cells;
// loss/reduce stores the three sums at sums[4 * pair .. 4 * pair + 2].
// loss/event_pair_bwd: with nE = sqrt(max(EE, norm_floor2)), nD = sqrt(max(DD, norm_floor2)),
//   l = || E / nE - D / nD ||^2, grad_j (+)= grad_scale * dl/drgb_j, grad_s (+)= grad_scale * dl/drgb_s,
// and invocation 0 writes (value_accumulate: adds) value_scale * l into values[value_index].
// loss/event_pair_value: that value alone (one invocation; no gradients).
struct EventPairPC {
  uint width;
  uint height;
  uint plane_first;
  uint plane_last;
  float theta_pos;
  float theta_neg;
  float eps;
  float norm_floor2;
  float grad_scale;
  float value_scale;
  uint value_accumulate;
  uint value_index;
  uint pair;
  uint counts_float;  // the count planes hold floats (binned events), else uints
  uint pool;          // side of the square pooling cells E and D are summed over (1: per pixel)
  uint pad2;
};

// Every pair of an exposure of F = 2..kEventPairsMaxFrames frames in one pass, at pool 1 when H*W
// is a multiple of 4 (engine/loss/event_loss.h), four pixels per invocation (vec4 / uvec4 reads):
// loss/event_pairs_f<F>: per pair q (j = q + 1, s from s_packed) the sums over the group's pixels of
// E*D, D*D, E*E and, for the time-reversed frame order, E*D', D'*D' (D' = L_{F-1-j} - L_{F-1-s})
// at sum index 5 q + 0..4, packed four to a vec4 column: partials[c * groups + group] holds sums
// 4 c .. 4 c + 3; loss/reduce (one workgroup per column) stores them at sums[4 c ..].
// loss/event_pairs_value: the forward order's value (sum over pairs of value_scale * l) into
// values[value_index] and, with `reversed`, the reversed order's into reversed_values[reversed_index].
// loss/event_pairs_bwd_f<F>: grad_f = grad_in_f + grad_scale * dl/drgb_f for every frame, from all
// pairs at once (E, D recomputed; no scratch planes); loss/event_pairs_bwd_f<F>_decode: that times
// decode'(sRGB render f), the render's gradient (what train/colour_decode_bwd would make of it).
EVF_CONST(uint, kEventPairsGroupSize, 64u)
EVF_CONST(uint, kEventPairsMaxFrames, 9u)
EVF_CONST(uint, kEventPairsSumsPerPair, 5u)
struct EventPairsPC {
  uint width;
  uint height;
  uint pairs;     // F - 1
  uint s_packed;  // pair q's earlier frame s in bits 4 q .. 4 q + 3
  float theta_pos;
  float theta_neg;
  float eps;
  float norm_floor2;
  float grad_scale;
  float value_scale;
  uint value_index;
  uint reversed;  // event_pairs_value: also the time-reversed order's value
  uint reversed_index;
  uint counts_float;  // the count planes hold floats (binned events), else uints
  uint groups;        // event_pairs: the dispatch's workgroups (partials per column)
  uint pad0;
};

// Warped-event loss (paper Eq. 6-7, engine/loss/warped_event_loss.h). One record per interval i
// of the virtual frames, frame j = i + 1; the view's planes hold, per interval, the measured
// events warped to t_j (M) and the interval's displacement (dx, dy), H*W floats each.
// loss/warped_event: per cell of pool x pool pixels, the sums over the cell's interior pixels
// (border pixels: both sides 0) of M and
//   P = -(Lx dx + Ly dy),  Lx, Ly: central differences of L = log(eps + luminance(rgb_j)),
// writes M and P into scratch planes 0 and 1 (a value per cell) and partials[g] = (sum M*P,
// sum P*P, sum M*M, 0);
// loss/reduce stores the sums at sums[4 * interval ..].
// loss/warped_event_bwd: l = || M / nM - P / nP ||^2 (floored norms as the event loss),
//   grad_j (+)= grad_scale * dl/drgb_j, and invocation 0 writes (value_accumulate: adds)
//   value_scale * l into values[value_index].
struct WarpedEventPC {
  uint width;
  uint height;
  uint interval;      // i: planes [3 i, 3 i + 2] of the view's buffer; sums at 4 i
  uint value_index;
  float eps;
  float norm_floor2;
  float grad_scale;
  float value_scale;
  uint value_accumulate;
  uint pool;  // side of the square pooling cells M and P are summed over (1: per pixel)
  uint pad1, pad2;
};


// loss/residual (the residual loss L_res, engine/loss/residual_loss.h), one dispatch per
// non-middle frame i: d = (F_i - F_N) - R_i per element; partials[partial_base + group].x = sum
// of d^2 over the group; grad_i += grad_scale * 2d and grad_N -= grad_scale * 2d.
struct ResidualPC {
  uint count;          // C*H*W
  uint partial_base;   // this frame's first partial
  float grad_scale;    // weight / (frames * count)
  uint pad0;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// loss/event_pair
EVF_BIND(kEventPairBindCounts, 0u, Counts)
EVF_BIND(kEventPairBindFrameS, 1u, FrameS)
EVF_BIND(kEventPairBindFrameJ, 2u, FrameJ)
EVF_BIND(kEventPairBindScratch, 3u, Scratch)
EVF_BIND(kEventPairBindPartials, 4u, Partials)
// loss/event_pair_bwd
EVF_BIND(kEventPairBwdBindFrameS, 0u, FrameS)
EVF_BIND(kEventPairBwdBindFrameJ, 1u, FrameJ)
EVF_BIND(kEventPairBwdBindScratch, 2u, Scratch)
EVF_BIND(kEventPairBwdBindSums, 3u, Sums)
EVF_BIND(kEventPairBwdBindGradS, 4u, GradS)
EVF_BIND(kEventPairBwdBindGradJ, 5u, GradJ)
EVF_BIND(kEventPairBwdBindValues, 6u, Values)
// loss/event_pair_value
EVF_BIND(kEventPairValueBindSums, 0u, Sums)
EVF_BIND(kEventPairValueBindValues, 1u, Values)
// loss/event_pairs_f<F> and loss/event_pairs_bwd_f<F>: the counts and frame k's render
// (texels), then the forward's partial sums, the backward's sums (texels), frame k's gradient and
// what it adds to (texels: a view of the same buffer, or the image terms' share of the frame);
// the _decode builds write the render's gradient instead.
EVF_BIND(kEventPairsBindCounts, 0u, Counts)
EVF_BIND(kEventPairsBindPartials, 1u, Partials)
EVF_BIND(kEventPairsBwdBindSums, 1u, Sums)
EVF_BIND(kEventPairsBindFrame0, 2u, Frame0)
EVF_BIND(kEventPairsBindFrame1, 3u, Frame1)
EVF_BIND(kEventPairsBindFrame2, 4u, Frame2)
EVF_BIND(kEventPairsBindFrame3, 5u, Frame3)
EVF_BIND(kEventPairsBindFrame4, 6u, Frame4)
EVF_BIND(kEventPairsBindFrame5, 7u, Frame5)
EVF_BIND(kEventPairsBindFrame6, 8u, Frame6)
EVF_BIND(kEventPairsBindFrame7, 9u, Frame7)
EVF_BIND(kEventPairsBindFrame8, 10u, Frame8)
EVF_BIND(kEventPairsBwdBindGrad0, 11u, Grad0)
EVF_BIND(kEventPairsBwdBindGrad1, 12u, Grad1)
EVF_BIND(kEventPairsBwdBindGrad2, 13u, Grad2)
EVF_BIND(kEventPairsBwdBindGrad3, 14u, Grad3)
EVF_BIND(kEventPairsBwdBindGrad4, 15u, Grad4)
EVF_BIND(kEventPairsBwdBindGrad5, 16u, Grad5)
EVF_BIND(kEventPairsBwdBindGrad6, 17u, Grad6)
EVF_BIND(kEventPairsBwdBindGrad7, 18u, Grad7)
EVF_BIND(kEventPairsBwdBindGrad8, 19u, Grad8)
EVF_BIND(kEventPairsBwdBindGradIn0, 20u, GradIn0)
EVF_BIND(kEventPairsBwdBindGradIn1, 21u, GradIn1)
EVF_BIND(kEventPairsBwdBindGradIn2, 22u, GradIn2)
EVF_BIND(kEventPairsBwdBindGradIn3, 23u, GradIn3)
EVF_BIND(kEventPairsBwdBindGradIn4, 24u, GradIn4)
EVF_BIND(kEventPairsBwdBindGradIn5, 25u, GradIn5)
EVF_BIND(kEventPairsBwdBindGradIn6, 26u, GradIn6)
EVF_BIND(kEventPairsBwdBindGradIn7, 27u, GradIn7)
EVF_BIND(kEventPairsBwdBindGradIn8, 28u, GradIn8)
// loss/event_pairs_value
EVF_BIND(kEventPairsValueBindSums, 0u, Sums)
EVF_BIND(kEventPairsValueBindValues, 1u, Values)
EVF_BIND(kEventPairsValueBindReversed, 2u, Reversed)
// loss/warped_event
EVF_BIND(kWarpedEventBindPlanes, 0u, Planes)
EVF_BIND(kWarpedEventBindFrame, 1u, Frame)
EVF_BIND(kWarpedEventBindScratch, 2u, Scratch)
EVF_BIND(kWarpedEventBindPartials, 3u, Partials)
// loss/warped_event_bwd
EVF_BIND(kWarpedEventBwdBindPlanes, 0u, Planes)
EVF_BIND(kWarpedEventBwdBindFrame, 1u, Frame)
EVF_BIND(kWarpedEventBwdBindScratch, 2u, Scratch)
EVF_BIND(kWarpedEventBwdBindSums, 3u, Sums)
EVF_BIND(kWarpedEventBwdBindGrad, 4u, Grad)
EVF_BIND(kWarpedEventBwdBindValues, 5u, Values)
// loss/pixel
EVF_BIND(kPixelLossBindA, 0u, A)
EVF_BIND(kPixelLossBindB, 1u, B)
EVF_BIND(kPixelLossBindGrad, 2u, Grad)
EVF_BIND(kPixelLossBindPartials, 3u, Partials)
// loss/reduce
EVF_BIND(kReduceBindPartials, 0u, Partials)
EVF_BIND(kReduceBindOut, 1u, Out)
// loss/ssim_bwd_h
EVF_BIND(kSsimBwdHBindD, 0u, D)
EVF_BIND(kSsimBwdHBindH, 1u, H)
// loss/ssim_bwd_v
EVF_BIND(kSsimBwdVBindA, 0u, A)
EVF_BIND(kSsimBwdVBindB, 1u, B)
EVF_BIND(kSsimBwdVBindH, 2u, H)
EVF_BIND(kSsimBwdVBindGrad, 3u, Grad)
EVF_BIND(kSsimBwdVBindGradIn, 4u, GradIn)  // a texel view of Grad: what an accumulating pass adds to
// loss/ssim_h
EVF_BIND(kSsimHBindA, 0u, A)
EVF_BIND(kSsimHBindB, 1u, B)
EVF_BIND(kSsimHBindH, 2u, H)
// loss/ssim_v
EVF_BIND(kSsimVBindA, 0u, A)
EVF_BIND(kSsimVBindB, 1u, B)
EVF_BIND(kSsimVBindH, 2u, H)
EVF_BIND(kSsimVBindD, 3u, D)
EVF_BIND(kSsimVBindPartials, 4u, Partials)
// loss/residual
EVF_BIND(kResidualBindFrame, 0u, Frame)
EVF_BIND(kResidualBindMid, 1u, Mid)
EVF_BIND(kResidualBindPrior, 2u, Prior)
EVF_BIND(kResidualBindGradFrame, 3u, GradFrame)
EVF_BIND(kResidualBindGradMid, 4u, GradMid)
EVF_BIND(kResidualBindPartials, 5u, Partials)

#ifdef __cplusplus
// Frame k's bindings, by k.
inline constexpr BindSlot kEventPairsBindFrames[] = {
    kEventPairsBindFrame0, kEventPairsBindFrame1, kEventPairsBindFrame2, kEventPairsBindFrame3, kEventPairsBindFrame4,
    kEventPairsBindFrame5, kEventPairsBindFrame6, kEventPairsBindFrame7, kEventPairsBindFrame8};
inline constexpr BindSlot kEventPairsBwdBindGrads[] = {
    kEventPairsBwdBindGrad0, kEventPairsBwdBindGrad1, kEventPairsBwdBindGrad2, kEventPairsBwdBindGrad3,
    kEventPairsBwdBindGrad4, kEventPairsBwdBindGrad5, kEventPairsBwdBindGrad6, kEventPairsBwdBindGrad7,
    kEventPairsBwdBindGrad8};
inline constexpr BindSlot kEventPairsBwdBindGradIns[] = {
    kEventPairsBwdBindGradIn0, kEventPairsBwdBindGradIn1, kEventPairsBwdBindGradIn2, kEventPairsBwdBindGradIn3,
    kEventPairsBwdBindGradIn4, kEventPairsBwdBindGradIn5, kEventPairsBwdBindGradIn6, kEventPairsBwdBindGradIn7,
    kEventPairsBwdBindGradIn8};
static_assert(sizeof(kEventPairsBindFrames) / sizeof(BindSlot) == kEventPairsMaxFrames);
#endif

EVF_NAMESPACE_END
#endif
