// Optical flow from events by contrast maximisation: the push constants, workgroup sizes and
// bindings shared by engine/flow (C++) and shaders/flow (GLSL).
//
// One exposure at a time: each interval j = [t_j, t_{j+1}] of its virtual frames has its own flow,
// a grid of (n + 1) x (n + 1) nodes (n x n tiles over the image; node (a, b) sits at pixel
// position (a W / n, b H / n)), interpolated bilinearly to every pixel; a node holds the
// displacement in pixels over its interval. The flow is piecewise constant in time, so an event
// at pixel x and time t moves to time t_r by sum_j lever_j u_j(x), lever_j = the signed length
// of [t, t_r] inside interval j, in units of that interval. Every event of the exposure is warped
// to three reference times (start, middle, end) and voted bilinearly into that reference's image
// of warped events (IWE).
//
// Events are stored pixel by pixel (CSR: pixel_first[H * W + 1] into event_time[], each pixel's
// events in time order), times normalised to the exposure ([0, 1]).
#ifndef EVF_FLOW_LAYOUT_H
#define EVF_FLOW_LAYOUT_H
#include "common/shared_prelude.h"
EVF_NAMESPACE_BEGIN

EVF_CONST(uint, kFlowGroupSize, 256u)
EVF_CONST(uint, kFlowRefs, 3u)          // reference times per problem: window start, middle, end
EVF_CONST(uint, kFlowMaxIntervals, 16u)  // intervals per exposure
EVF_CONST(float, kFlowVoteScale, 65536.0f)  // IWE votes are fixed point (exact integer atomics)
EVF_CONST(int, kFlowBlurRadius, 2)          // Gaussian blur of the IWE: 5 taps (the next: 1e-4)
EVF_CONST(float, kFlowBlurSigma, 0.7f)      // its standard deviation, pixels

// Per interval j (a vec4 in the Intervals buffer): (start, end, 1 / (end - start), unused), in
// normalised exposure time. Reference r's time is r / 2.

// Pixels with events, the busiest first: pixel_order[busy].
// flow/vote: one invocation per event (event_slot[e]: the index k of its pixel in pixel_order);
// adds its bilinear vote (scaled by kFlowVoteScale) to iwe[r * image_height * image_width +
// pixel'] for r = 0..2.
// flow/flow_grad: the same grid; grad_field[(j * H * W + pixel) * 2 + c] = dLoss / du_j(pixel).
// The IWEs may be coarser than the sensor (coarse to fine in image scale): pixel centre c of the
// sensor lands at c / scale in an image_width x image_height IWE.
struct FlowEventsPC {
  uint width;  // the sensor
  uint height;
  uint intervals;
  uint tiles;  // n: tiles per side of the node grid
  uint image_width;
  uint image_height;
  float scale;
  uint busy;    // pixels with events: pixel_order[0 .. busy)
  uint stride;  // every stride-th event (coarse levels need fewer)
  uint events;  // of the exposure
  uint pad1, pad2;
};

// flow/positions: the same grid; positions[m * busy + k] = C_m+1 (m < intervals) and P(t_r)
// (m = intervals + r) of pixel pixel_order[k], read by flow/vote and flow/flow_grad.
EVF_CONST(uint, kFlowPositionsPerPixel, kFlowMaxIntervals + kFlowRefs)

// flow/blur: one invocation per pixel of `images` images; the (2 kFlowBlurRadius + 1)-tap Gaussian along x (axis 0) or
// y (axis 1), zero outside the image. fixed_input = 1 reads the IWE's fixed-point votes.
struct FlowBlurPC {
  uint width;
  uint height;
  uint images;
  uint axis;
  uint fixed_input;
  uint pad0, pad1, pad2;
};

// flow/contrast: per image (reference), G = sum over pixels of |grad B|^2 with central
// differences (zero outside); writes one partial sum per workgroup (partials[image * groups +
// group], groups = ceil(H W / kFlowGroupSize)) and the adjoint dLoss/dB = scale[image] * dG/dB.
struct FlowContrastPC {
  uint width;
  uint height;
  uint images;
  uint groups;  // workgroups per image
};

// flow/adjoint_quads: one invocation per footprint position of `images` width x height adjoint
// images: quads[(image * (height + 1) + qy) * (width + 1) + qx] = the four adjoint values of the
// bilinear footprint whose top-left pixel is (qx - 1, qy - 1), zero outside. flow/flow_grad reads
// these instead of the adjoint images.
struct FlowQuadsPC {
  uint width;
  uint height;
  uint images;
  uint pad0;
};

// flow/node_reduce: one workgroup per (tile, interval): tile_grad[((j * tiles^2 + tile) * 4 + c)]
// = the sum over the tile's pixels of the bilinear weight of its corner c (0: (a, b), 1: (a+1, b),
// 2: (a, b+1), 3: (a+1, b+1)) times grad_field; the host adds them onto the nodes.
struct FlowNodeReducePC {
  uint width;
  uint height;
  uint intervals;
  uint tiles;
};

// Storage-buffer bindings: EVF_BIND(constant, index, GLSL block name).
// flow/vote
EVF_BIND(kFlowVoteBindEventSlot, 0u, EventSlot)
EVF_BIND(kFlowVoteBindEventTime, 1u, EventTime)
EVF_BIND(kFlowVoteBindIntervals, 2u, Intervals)
EVF_BIND(kFlowVoteBindNodes, 3u, Nodes)
EVF_BIND(kFlowVoteBindIwe, 4u, Iwe)
EVF_BIND(kFlowVoteBindPixelOrder, 5u, PixelOrder)
EVF_BIND(kFlowVoteBindPositions, 6u, Positions)
// flow/positions
EVF_BIND(kFlowPositionsBindPixelOrder, 0u, PixelOrder)
EVF_BIND(kFlowPositionsBindIntervals, 1u, Intervals)
EVF_BIND(kFlowPositionsBindNodes, 2u, Nodes)
EVF_BIND(kFlowPositionsBindPositions, 3u, Positions)
// flow/blur
EVF_BIND(kFlowBlurBindSrc, 0u, Src)
EVF_BIND(kFlowBlurBindDst, 1u, Dst)
// flow/contrast
EVF_BIND(kFlowContrastBindBlurred, 0u, Blurred)
EVF_BIND(kFlowContrastBindScale, 1u, Scale)
EVF_BIND(kFlowContrastBindAdjoint, 2u, Adjoint)
EVF_BIND(kFlowContrastBindPartials, 3u, Partials)
// flow/flow_grad
EVF_BIND(kFlowGradBindPixelFirst, 0u, PixelFirst)
EVF_BIND(kFlowGradBindEventTime, 1u, EventTime)
EVF_BIND(kFlowGradBindIntervals, 2u, Intervals)
EVF_BIND(kFlowGradBindQuads, 4u, Quads)
EVF_BIND(kFlowGradBindGradField, 5u, GradField)
EVF_BIND(kFlowGradBindPixelOrder, 6u, PixelOrder)
EVF_BIND(kFlowGradBindPositions, 7u, Positions)
// flow/adjoint_quads
EVF_BIND(kFlowQuadsBindAdjoint, 0u, Adjoint)
EVF_BIND(kFlowQuadsBindQuads, 1u, Quads)
// flow/node_reduce
EVF_BIND(kFlowReduceBindGradField, 0u, GradField)
EVF_BIND(kFlowReduceBindTileGrad, 1u, TileGrad)

EVF_NAMESPACE_END
#endif
