#version 450
// Warped-event loss, backward part of one interval (loss_layout.h, WarpedEventPC): the gradient
// of l = || M/nM - P/nP ||^2 w.r.t. frame j's RGB, added into its gradient image (pixel q feeds
// the central differences of its four neighbours, each of which takes its pooling cell's dl/dP),
// and the interval's value.
#extension GL_GOOGLE_include_directive : require
#include "loss/loss_layout.h"
#include "common/dispatch.glsl"
layout(local_size_x = kLossGroupSize) in;
layout(std430, binding = kWarpedEventBwdBindPlanes) readonly buffer Planes { float planes[]; };
layout(std430, binding = kWarpedEventBwdBindFrame) readonly buffer Frame { float frame[]; };
layout(std430, binding = kWarpedEventBwdBindScratch) readonly buffer Scratch { float scratch[]; };
layout(std430, binding = kWarpedEventBwdBindSums) readonly buffer Sums { float sums[]; };
layout(std430, binding = kWarpedEventBwdBindGrad) buffer Grad { float grad[]; };
layout(std430, binding = kWarpedEventBwdBindValues) buffer Values { float values[]; };
layout(push_constant) uniform PC { WarpedEventPC pc; };
#include "loss/event_math.glsl"
#include "loss/warped_math.glsl"

float mp, pp, mm;  // the interval's sums

// dl/dP at pixel (x, y): its cell's, 0 outside the interior.
float dl_dp(uint x, uint y) {
  if (!warped_interior(x, y)) return 0.0;
  uint cw = event_cells(pc.width, pc.pool), cells = cw * event_cells(pc.height, pc.pool), c = (y / pc.pool) * cw + x / pc.pool;
  return event_pair_dl_dd(scratch[c], scratch[cells + c], mp, pp, mm, pc.norm_floor2);
}

void main() {
  uint hw = pc.width * pc.height;
  uint q = evf_linear_invocation(kLossGroupSize);
  mp = sums[4u * pc.interval];
  pp = sums[4u * pc.interval + 1u];
  mm = sums[4u * pc.interval + 2u];
  if (q == 0u) {
    float v = pc.value_scale * event_pair_loss(mp, pp, mm, pc.norm_floor2);
    values[pc.value_index] = pc.value_accumulate != 0u ? values[pc.value_index] + v : v;
  }
  if (q >= hw) return;
  uint x = q % pc.width, y = q / pc.width, dx = warped_plane(1u, hw), dy = warped_plane(2u, hw);
  // P(n) = -(Lx(n) dx(n) + Ly(n) dy(n)) and Lx(n) = (L(n + 1) - L(n - 1)) / 2: L(q) enters P(q + 1)
  // with -dx(q + 1) * (-1/2) and P(q - 1) with -dx(q - 1) * (1/2); the same along y.
  float gl = 0.0;
  if (x + 1u < pc.width) gl += 0.5 * dl_dp(x + 1u, y) * planes[dx + q + 1u];
  if (x > 0u) gl -= 0.5 * dl_dp(x - 1u, y) * planes[dx + q - 1u];
  if (y + 1u < pc.height) gl += 0.5 * dl_dp(x, y + 1u) * planes[dy + q + pc.width];
  if (y > 0u) gl -= 0.5 * dl_dp(x, y - 1u) * planes[dy + q - pc.width];
  vec3 c = vec3(frame[q], frame[hw + q], frame[2u * hw + q]);
  vec3 g = pc.grad_scale * gl * event_log_luma_grad(c, pc.eps);
  grad[q] += g.r;
  grad[hw + q] += g.g;
  grad[2u * hw + q] += g.b;
}
