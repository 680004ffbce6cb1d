// Neural layers: push constants, tile sizes and bindings shared by engine/nn (C++) and
// shaders/nn (GLSL). Tensors are NCHW float32: element (b, c, y, x) of a batch of N images at
// ((b * C + c) * H + y) * W + x.
#ifndef EVF_NN_LAYOUT_H
#define EVF_NN_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

// Convolutions as one implicit GEMM, C[m][n] = sum_k A(m, k) B(k, n) (nn/gemm.glsl), in three
// forms over a KxK kernel (K = 1 or 3), padding K / 2, stride 1 or 2, weights W[co][ci][ky][kx],
// over a batch of images ("pixel" below runs over every image's pixels, image after image, so n
// and k count batch x pixels; padding is per image):
//   forward      (nn/conv_fwd):        m = co, n = output pixel, k = (ci, ky, kx);
//                                      A = W, B = input at the tap (0 outside), C + bias[co] -> y
//   input grad   (nn/conv_bwd_input):  m = ci, n = input pixel, k = (co, ky, kx);
//                                      A = W transposed, B = dy at the output pixel whose tap lands
//                                      on n (0 where none does) -> dx (written or added)
//   weight grad  (nn/conv_bwd_weight): m = co, n = (ci, ky, kx) and one more column for the bias
//                                      (B = 1), k = output pixel, split into chunks of
//                                      pixels_per_split; each chunk writes its partial sums
//                                      partial[split][m][n], which nn/conv_reduce adds in split
//                                      order (no float atomics: the sums are deterministic).
// A workgroup computes a kGemmTileM x kGemmTileN tile of C, each invocation kGemmThreadM x
// kGemmThreadN of it, through shared-memory tiles of kGemmTileK values of k. The narrow
// variants (kernel names ending in _narrow) have a tile of kGemmNarrowTileM rows, each invocation
// kGemmNarrowThreadM of them, for layers with few output channels; the tiny ones (_tiny) one row
// of four per invocation and a single SIMD group per workgroup (kGemmTinyTileN / kGemmThreadN
// invocations), for at most kGemmTinyTileM rows (the LDI's last layer has one): the narrow tile
// spends 15 of its 16 rows on nothing there, and its barriers stop 32 groups of lanes, not one.
// The tiny tile stages nothing in shared memory: each value of B feeds one invocation only. The
// narrow tile is 160 columns wide so that the weight gradient of a 16-channel 3x3 layer (145
// columns: 144 weights and the bias) fits one tile, not two of 128.
EVF_CONST(uint, kGemmThreadM, 8u)
EVF_CONST(uint, kGemmThreadN, 16u)
EVF_CONST(uint, kGemmTileM, 64u)
EVF_CONST(uint, kGemmTileN, 128u)
EVF_CONST(uint, kGemmTileK, 32u)
EVF_CONST(uint, kGemmNarrowThreadM, 4u)
EVF_CONST(uint, kGemmNarrowTileM, 16u)
EVF_CONST(uint, kGemmNarrowThreadN, 20u)
EVF_CONST(uint, kGemmNarrowTileN, 160u)
EVF_CONST(uint, kGemmTinyThreadM, 4u)
EVF_CONST(uint, kGemmTinyTileM, 4u)
EVF_CONST(uint, kGemmTinyTileN, 128u)
// Shared memory of a GEMM workgroup: the A and B tiles, kGemmTileK rows each.
EVF_CONST(uint, kGemmSharedBytes, kGemmTileK * (kGemmTileM + kGemmTileN) * 4u)
EVF_CONST(uint, kGemmNarrowSharedBytes, kGemmTileK * (kGemmNarrowTileM + kGemmNarrowTileN) * 4u)
struct ConvPC {
  uint in_c, in_h, in_w;
  uint out_c, out_h, out_w;
  uint ksize;   // 1 or 3
  uint stride;  // 1 or 2
  uint pad;     // ksize / 2
  uint gemm_m, gemm_n, gemm_k;
  uint tiles_n;           // workgroups along n (the linear group index is tile_m * tiles_n + tile_n)
  uint pixels_per_split;  // weight grad: values of k per split, a multiple of kGemmTileK
  uint accumulate;        // input grad: 1 adds into dx; reduce: 1 adds into dw and db
  uint splits;            // reduce: partial sums to add
};

// Direct 3x3 convolution, stride 1, padding 1 (nn/conv3x3_direct; CPU drivers, where every
// buffer access is a loop over the SIMD lanes and the GEMM's gathers of 9 taps per input value
// cost more than its multiply-adds). One invocation computes a block of 4 x kDirectRows output
// pixels for kDirectGroup output channels: per input channel it reads each of the block's
// kDirectRows + 2 input rows as three vec4s (the row's 4 pixels and its neighbours on each side)
// and the 9 taps' weights of its channels as vec4s, then does 9 x 4 x kDirectRows x kDirectGroup
// multiply-adds from registers. Rows are read as vec4s where the width is a multiple of 4
// (nn/conv3x3_direct), else one value at a time (nn/conv3x3_direct_any). The weights are
// rearranged to WT[ci][tap][co], co padded to kDirectGroup (nn/conv_weight_t): for the forward
// WT[ci][tap][co] = W[co][ci][tap]; for the input gradient, a convolution of dy,
// WT[co][tap][ci] = W[co][ci][8 - tap] (the flipped kernel, transposed).
EVF_CONST(uint, kDirectRows, 4u)
EVF_CONST(uint, kDirectGroup, 16u)
// The "_checked" builds, for GPU-assisted validation, take blocks of 4 x 1 pixels and groups of 4
// channels: the same index arithmetic, but the layer's check on every access makes the full
// kernels (hundreds of live values across as many branches) take minutes to compile on lavapipe.
EVF_CONST(uint, kDirectRowsChecked, 1u)
EVF_CONST(uint, kDirectGroupChecked, 4u)
EVF_CONST(uint, kDirectGroupSize, 16u)  // invocations per workgroup
struct DirectConvPC {
  uint in_c, out_c, h, w;  // input and output channels; both images are h x w
  uint out_pad;            // out_c rounded up to kDirectGroup (WT's row length)
  uint blocks_x, blocks_y; // 4-pixel columns and kDirectRows-pixel rows of blocks per image
  uint groups;             // output channel groups (out_pad / kDirectGroup)
  uint images;
  uint bias;               // 1: add bias[co] (the forward)
  uint accumulate;         // 1: add into y (the input gradient's accumulating form)
  uint pad0;
};
// nn/conv3x3_direct_dw: the weight gradient's partial sums, one invocation per (split, channel
// group, input channel); a split is blocks_per_split consecutive blocks (image after image).
EVF_CONST(uint, kDirectBlocksPerSplit, 128u)  // 2048 pixels, as the GEMM's kPixelsPerSplit
struct DirectGradPC {
  uint in_c, out_c, h, w;
  uint blocks_x, blocks_y;  // blocks per image
  uint groups;              // output channel groups of kDirectGroup
  uint images;
  uint blocks_per_split, splits;
  uint pad0, pad1;
};
// nn/conv_weight_t: WT from W, one invocation per WT value (zeros in the padding).
struct WeightTPC {
  uint in_c, out_c;  // the layer's
  uint rows, cols;   // WT is [rows][9][cols]: rows = in_c, cols = out_pad (forward) or the reverse
  uint flip;         // 1: the input gradient's flipped, transposed kernel
  uint pad0, pad1, pad2;
};

// Element-wise layers, one invocation per value: ReLU, sigmoid (forward from x, backward from
// the forward's output y and dy), and x2 nearest up-sampling to out_h x out_w (at most 2 h x 2 w:
// out(c, y, x) = in(c, y / 2, x / 2); its backward adds the up to four outputs of each input).
EVF_CONST(uint, kNnGroupSize, 256u)
struct PointwisePC {
  uint count;        // values (channels * h * w of the output)
  uint channels;     // up-sampling: channels; others unused
  uint in_h, in_w;   // up-sampling: the low-resolution size
  uint out_h, out_w; // up-sampling: the high-resolution size
  uint accumulate;   // backward: 1 adds into the gradient instead of writing it
  uint pad0;
};
// conv_reduce: one invocation per weight (and bias) value.
EVF_CONST(uint, kReduceGroupSize, 256u)

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// nn/conv_fwd, nn/conv_fwd_narrow
EVF_BIND(kConvFwdBindX, 0u, X)
EVF_BIND(kConvFwdBindW, 1u, Weight)
EVF_BIND(kConvFwdBindBias, 2u, Bias)
EVF_BIND(kConvFwdBindY, 3u, Y)
// nn/conv_bwd_input, nn/conv_bwd_input_narrow
EVF_BIND(kConvBwdInputBindDy, 0u, Dy)
EVF_BIND(kConvBwdInputBindW, 1u, Weight)
EVF_BIND(kConvBwdInputBindDx, 2u, Dx)
// nn/conv_bwd_weight, nn/conv_bwd_weight_narrow
EVF_BIND(kConvBwdWeightBindX, 0u, X)
EVF_BIND(kConvBwdWeightBindDy, 1u, Dy)
EVF_BIND(kConvBwdWeightBindPartial, 2u, Partial)
// nn/conv3x3_direct
EVF_BIND(kDirectBindX, 0u, X)
EVF_BIND(kDirectBindWT, 1u, WeightT)
EVF_BIND(kDirectBindBias, 2u, Bias)
EVF_BIND(kDirectBindY, 3u, Y)
// nn/conv3x3_direct_dw
EVF_BIND(kDirectDwBindX, 0u, X)
EVF_BIND(kDirectDwBindDy, 1u, Dy)
EVF_BIND(kDirectDwBindPartial, 2u, Partial)
// nn/conv_weight_t
EVF_BIND(kWeightTBindW, 0u, Weight)
EVF_BIND(kWeightTBindWT, 1u, WeightT)
// nn/conv_reduce
EVF_BIND(kConvReduceBindPartial, 0u, Partial)
EVF_BIND(kConvReduceBindDw, 1u, Dw)
EVF_BIND(kConvReduceBindDb, 2u, Db)
// nn/relu, nn/sigmoid, nn/upsample
EVF_BIND(kActFwdBindX, 0u, X)
EVF_BIND(kActFwdBindY, 1u, Y)
// nn/relu_bwd, nn/sigmoid_bwd, nn/upsample_bwd (relu_bwd and sigmoid_bwd read the forward's
// output y, upsample_bwd does not bind it)
EVF_BIND(kActBwdBindY, 0u, Y)
EVF_BIND(kActBwdBindDy, 1u, Dy)
EVF_BIND(kActBwdBindDx, 2u, Dx)

EVF_NAMESPACE_END
#endif
