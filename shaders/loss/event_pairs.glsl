// What loss/event_pairs_f<F> and loss/event_pairs_bwd_f<F> share (loss_layout.h): an exposure of
// EVF_EVENT_FRAMES = F frames and its pairs q = 0 .. F-2 (frame j = q + 1, s from the push
// constants), four pixels (quad q4 of quads) per invocation. The lists expand with constant
// indices, so every per-frame and per-pair value stays in registers: EVF_FRAMES(X) is X(k) for
// each frame k, EVF_PAIRS(X) X(q) for each pair q.
#ifndef EVF_EVENT_FRAMES
#error EVF_EVENT_FRAMES (the exposure's frame count) must be defined
#endif
#define EVF_FRAME_COUNT EVF_EVENT_FRAMES
#include "common/frame_list.glsl"
#define EVF_PAIRS(X) EVF_FRAMES_BUT_LAST(X)
#define EVF_PAIR_COUNT (EVF_EVENT_FRAMES - 1)

layout(binding = kEventPairsBindCounts) uniform usamplerBuffer Counts;  // R32UI
#define EVF_FRAME_BINDING(k) layout(binding = kEventPairsBindFrame##k) uniform samplerBuffer Frame##k;
EVF_FRAMES(EVF_FRAME_BINDING)

// Pair q's earlier frame.
uint pair_s(uint q) { return (pc.s_packed >> (4u * q)) & 0xFu; }

// Four pixels' plane values: uint counts, or (binned events) the bits of float amounts.
vec4 plane_amounts(uint i) {
  uvec4 v = evf_texel_uvec4(Counts, i);
  return pc.counts_float != 0u ? uintBitsToFloat(v) : vec4(v);
}

// Four pixels' signed amount of interval k: theta_pos * positive - theta_neg * negative.
vec4 interval_amount(uint k, uint q4, uint quads) {
  uint base = k * 2u * quads;
  return pc.theta_pos * plane_amounts(base + q4) - pc.theta_neg * plane_amounts(base + quads + q4);
}

// E of pair (s, q + 1): the intervals s .. q added in order from zero (the ones before s add +0,
// which leaves the sum as it is: the same bits as a sum that starts at s).
#define EVF_PAIR_E(q, E, e)                                      \
  {                                                              \
    uint s_ = pair_s(q);                                         \
    E = vec4(0.0);                                               \
    for (uint k_ = 0u; k_ <= q; ++k_) E += k_ >= s_ ? e[k_] : vec4(0.0); \
  }

// v[i] with i a runtime index in [lo, hi] (constant bounds: registers, not an indexed array).
#define EVF_PICK(out, v, i, lo, hi)                                          \
  {                                                                          \
    out = v[lo];                                                             \
    for (uint f_ = (lo) + 1u; f_ <= (hi); ++f_) out = (i) == f_ ? v[f_] : out; \
  }
