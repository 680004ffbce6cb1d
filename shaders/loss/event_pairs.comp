#version 450
// Event loss, forward part of every pair of an exposure at once (pool 1, H*W a multiple of 4;
// loss_layout.h, EventPairsPC): per pair q the group's sums of E*D, D*D, E*E and the time-reversed
// frame order's E*D', D'*D', four pixels per invocation. Each interval's counts and each frame's
// log-luminance are read once for all pairs, and nothing per pixel is stored: the backward
// (loss/event_pairs_bwd) recomputes E and D.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kEventPairsGroupSize) in;
layout(push_constant) uniform PC { EventPairsPC pc; };
#include "common/texel.glsl"
#include "loss/event_math.glsl"
#include "loss/event_pairs.glsl"
layout(std430, binding = kEventPairsBindPartials) writeonly buffer Partials { vec4 partials[]; };

#define EVF_SUM_COUNT (kEventPairsSumsPerPair * EVF_PAIR_COUNT)
#define EVF_SUM_VEC4S ((EVF_SUM_COUNT + 3) / 4)
shared vec4 red[EVF_SUM_VEC4S][kEventPairsGroupSize];

#define EVF_INTERVAL(k) e[k] = interval_amount(k, q4, quads);
#define EVF_LOG_LUMA(k) \
  L[k] = event_log_luma(texelFetch(Frame##k, int(q4)), texelFetch(Frame##k, int(quads + q4)), \
                        texelFetch(Frame##k, int(2u * quads + q4)), pc.eps);
// Pair q's five sums into v at 5 q: the forward order's D = L_j - L_s, the reversed order's
// D' = L_{F-1-j} - L_{F-1-s}.
#define EVF_PAIR_SUMS(q)                                                                        \
  {                                                                                             \
    vec4 E, Ls, Lrs;                                                                            \
    EVF_PAIR_E(q, E, e)                                                                         \
    uint s = pair_s(q);                                                                         \
    EVF_PICK(Ls, L, s, 0u, q)                                                                   \
    EVF_PICK(Lrs, L, EVF_PAIR_COUNT - s, EVF_PAIR_COUNT - q, EVF_PAIR_COUNT)                    \
    vec4 D = L[q + 1] - Ls, Dr = L[EVF_PAIR_COUNT - 1 - q] - Lrs;                               \
    v[5 * q] = dot(E, D);                                                                       \
    v[5 * q + 1] = dot(D, D);                                                                   \
    v[5 * q + 2] = dot(E, E);                                                                   \
    v[5 * q + 3] = dot(E, Dr);                                                                  \
    v[5 * q + 4] = dot(Dr, Dr);                                                                 \
  }

void main() {
  uint quads = pc.width * pc.height / 4u, q4 = evf_linear_invocation(kEventPairsGroupSize);
  uint lid = gl_LocalInvocationIndex;
  float v[4 * EVF_SUM_VEC4S];
  for (uint i = 0u; i < 4u * EVF_SUM_VEC4S; ++i) v[i] = 0.0;
  if (q4 < quads) {
    vec4 e[EVF_PAIR_COUNT], L[EVF_EVENT_FRAMES];
    EVF_PAIRS(EVF_INTERVAL)
    EVF_FRAMES(EVF_LOG_LUMA)
    EVF_PAIRS(EVF_PAIR_SUMS)
  }
  // Fixed-order group sums: 8 invocations add 8 values each in order, then one adds their 8.
  // Loops of no trip outside the invocations that add (an `if` skips nothing on CPU drivers).
  for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) red[c][lid] = vec4(v[4 * c], v[4 * c + 1], v[4 * c + 2], v[4 * c + 3]);
  barrier();
  uint n = lid < 8u ? 8u : 0u;
  vec4 part[EVF_SUM_VEC4S];
  for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) part[c] = vec4(0.0);
  for (uint k = 0u; k < n; ++k)
    for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) part[c] += red[c][8u * lid + k];
  for (uint t = n != 0u ? 1u : 0u; t > 0u; --t)
    for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) red[c][8u * lid] = part[c];
  barrier();
  n = lid == 0u ? 8u : 0u;
  for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) part[c] = vec4(0.0);
  for (uint k = 0u; k < n; ++k)
    for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) part[c] += red[c][8u * k];
  uint group = evf_linear_group();
  for (uint t = n != 0u && group < pc.groups ? 1u : 0u; t > 0u; --t)
    for (uint c = 0u; c < EVF_SUM_VEC4S; ++c) partials[c * pc.groups + group] = part[c];
}
