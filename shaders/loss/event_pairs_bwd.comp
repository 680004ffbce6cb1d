#version 450
// Event loss, backward part of every pair of an exposure at once, after loss/event_pairs_f<F> and
// its sums (loss_layout.h, EventPairsPC): each frame's dl/dL from all the pairs it takes part in,
// then one addition into each frame's gradient image, four pixels per invocation. E and D are
// recomputed as the forward computed them.
// EVF_DECODE_RENDER (the "_decode" builds, when this term is the last to add to the frames'
// gradients): the sum is also taken through the sRGB decode of each frame's render, so that the
// output is the render's gradient and the image model's decode_bwd pass over every frame is not
// needed. decode' comes from the linear frame alone (evf_srgb_decode_deriv_of_linear): decode_bwd's
// values up to rounding, and no read of the renders (their planes, read beside the frames', were a
// sixth of this kernel).
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kEventPairsGroupSize) in;
layout(push_constant) uniform PC { EventPairsPC pc; };
#include "common/texel.glsl"
#include "loss/event_math.glsl"
#include "loss/event_pairs.glsl"
layout(binding = kEventPairsBwdBindSums) uniform samplerBuffer Sums;  // the pairs' sums (floats)
// Frame k's gradient image, written, and what it adds to, read as texels: a view of the same
// buffer (each element read, then written, by its own invocation alone) or another image.
#define EVF_GRAD_BINDING(k)                                                                  \
  layout(std430, binding = kEventPairsBwdBindGrad##k) writeonly buffer Grad##k { vec4 grad##k[]; }; \
  layout(binding = kEventPairsBwdBindGradIn##k) uniform samplerBuffer GradIn##k;
EVF_FRAMES(EVF_GRAD_BINDING)
#ifdef EVF_DECODE_RENDER
#include "common/srgb.glsl"
#define EVF_OUT(k, i, v) grad##k[i] = (v) * evf_srgb_decode_deriv_of_linear(texelFetch(Frame##k, int(i)));
#else
#define EVF_OUT(k, i, v) grad##k[i] = (v);
#endif

#define EVF_INTERVAL(k) e[k] = interval_amount(k, q4, quads);
#define EVF_LUMA(k)                                                                               \
  y[k] = event_luma(texelFetch(Frame##k, int(q4)), texelFetch(Frame##k, int(quads + q4)),         \
                    texelFetch(Frame##k, int(2u * quads + q4)));                                  \
  L[k] = log(pc.eps + max(vec4(0.0), y[k]));                                                      \
  G[k] = vec4(0.0);
// Pair q's dl/dD, into its later frame's dl/dL with a plus and its earlier frame's with a minus.
#define EVF_PAIR_GRAD(q)                                                                      \
  {                                                                                           \
    vec4 E, Ls;                                                                               \
    EVF_PAIR_E(q, E, e)                                                                       \
    uint s = pair_s(q);                                                                       \
    EVF_PICK(Ls, L, s, 0u, q)                                                                 \
    float ed = evf_texel_float(Sums, 5u * q), dd = evf_texel_float(Sums, 5u * q + 1u);         \
    float ee = evf_texel_float(Sums, 5u * q + 2u);                                             \
    vec4 g = pc.grad_scale * event_pair_dl_dd(E, L[q + 1] - Ls, ed, dd, ee, pc.norm_floor2);  \
    G[q + 1] += g;                                                                            \
    for (uint f = 0u; f <= q; ++f) G[f] -= s == f ? g : vec4(0.0);                            \
  }
#define EVF_FRAME_GRAD(k)                                                                                   \
  EVF_OUT(k, q4, texelFetch(GradIn##k, int(q4)) + G[k] * event_log_luma_grad(y[k], kEventLuma.r, pc.eps))   \
  EVF_OUT(k, quads + q4,                                                                                    \
          texelFetch(GradIn##k, int(quads + q4)) + G[k] * event_log_luma_grad(y[k], kEventLuma.g, pc.eps))  \
  EVF_OUT(k, 2u * quads + q4,                                                                               \
          texelFetch(GradIn##k, int(2u * quads + q4)) + G[k] * event_log_luma_grad(y[k], kEventLuma.b, pc.eps))

void main() {
  uint quads = pc.width * pc.height / 4u, q4 = evf_linear_invocation(kEventPairsGroupSize);
  if (q4 >= quads) return;
  vec4 e[EVF_PAIR_COUNT], y[EVF_EVENT_FRAMES], L[EVF_EVENT_FRAMES], G[EVF_EVENT_FRAMES];
  EVF_PAIRS(EVF_INTERVAL)
  EVF_FRAMES(EVF_LUMA)
  EVF_PAIRS(EVF_PAIR_GRAD)
  EVF_FRAMES(EVF_FRAME_GRAD)
}
