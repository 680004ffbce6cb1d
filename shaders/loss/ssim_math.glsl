// SSIM maths shared by the forward (ssim_h, ssim_v) and the backward (ssim_bwd_h, ssim_bwd_v).
//
// Definition (per channel c, per pixel p = (y, x) of an H x W image):
//   w(dy, dx) = g[dy + 5] * g[dx + 5],  g[k] = exp(-(k-5)^2 / (2 * 1.5^2)) / sum_j exp(...)
//   E[f](p)   = sum over |dy|,|dx| <= 5 with p + (dy, dx) inside the image of w(dy, dx) f(p + (dy, dx))
// i.e. a "same"-size convolution with zero padding: taps that fall outside the image are dropped
// and the remaining weights are NOT renormalised (what F.conv2d(padding=5) computes in 3DGS).
//   mu_A = E[A], mu_B = E[B], s_AA = E[A^2] - mu_A^2, s_BB = E[B^2] - mu_B^2, s_AB = E[AB] - mu_A mu_B
//   SSIM(p) = (2 mu_A mu_B + C1)(2 s_AB + C2) / ((mu_A^2 + mu_B^2 + C1)(s_AA + s_BB + C2))
// SSIM needs s_AA and s_BB only as their sum, so the forward filters four moments, A, B, A^2 + B^2
// and AB: one vec4 a pixel.
// The window is separable and symmetric, so E[] is a horizontal then a vertical 11-tap pass.
//
// Backward: with m1 = E[A], m3 = E[A^2 + B^2], m5 = E[AB] and d_k(p) = dSSIM(p)/dm_k(p),
//   d(sum_p SSIM(p))/dA(q) = E[d1](q) + 2 A(q) E[d3](q) + B(q) E[d5](q)
// because the adjoint of the zero-padded symmetric convolution is the same convolution.

const float kSsimG[11] = float[11](1.028380084e-03, 7.598758135e-03, 3.600077213e-02, 1.093606895e-01,
                                   2.130055377e-01, 2.660117249e-01, 2.130055377e-01, 1.093606895e-01,
                                   3.600077213e-02, 7.598758135e-03, 1.028380084e-03);

struct SsimPixel {
  float ssim;
  float d1;  // dSSIM/dE[A]   (total: through mu_A, s_AA and s_AB)
  float d3;  // dSSIM/dE[A^2 + B^2]
  float d5;  // dSSIM/dE[AB]
};

// m = (E[A], E[B], E[A^2 + B^2], E[AB]).
SsimPixel ssim_eval(vec4 m, float c1, float c2) {
  float mu_a = m.x, mu_b = m.y;
  float mu2 = mu_a * mu_a + mu_b * mu_b;
  float s_sum = m.z - mu2;  // s_AA + s_BB
  float s_ab = m.w - mu_a * mu_b;
  float n1 = 2.0 * mu_a * mu_b + c1;
  float n2 = 2.0 * s_ab + c2;
  float den1 = mu2 + c1;
  float den2 = s_sum + c2;
  float inv = 1.0 / (den1 * den2);
  SsimPixel r;
  r.ssim = n1 * n2 * inv;
  // Partials w.r.t. mu_a, s_AA (the same as w.r.t. s_AA + s_BB), s_ab, then chained to m1, m3, m5.
  float d_mu_a = 2.0 * mu_b * n2 * inv - 2.0 * mu_a * r.ssim / den1;
  float d_s_aa = -r.ssim / den2;
  float d_s_ab = 2.0 * n1 * inv;
  r.d3 = d_s_aa;
  r.d5 = d_s_ab;
  r.d1 = d_mu_a - 2.0 * mu_a * d_s_aa - mu_b * d_s_ab;
  return r;
}

// Fixed-order workgroup sum of a vec4: 16 invocations each add 16 values in order, then one adds
// the 16 results in order (two barriers: barriers are costly on CPU drivers). Every invocation
// must call it; the result is valid in invocation 0. The loops' trip counts are 0 outside the
// invocations that add: a constant count would be unrolled, and on CPU drivers every SIMD vector
// of the workgroup would then run the loads, masked off, as loops over its lanes.
shared vec4 evf_loss_red[kLossGroupSize];
vec4 loss_group_sum(vec4 v) {
  uint lid = gl_LocalInvocationIndex;
  evf_loss_red[lid] = v;
  barrier();
  uint n = lid < 16u ? 16u : 0u;
  vec4 s = vec4(0.0);
  for (uint k = 0u; k < n; ++k) s += evf_loss_red[lid * 16u + k];
  if (n != 0u) evf_loss_red[lid * 16u] = s;
  barrier();
  vec4 total = vec4(0.0);
  n = lid == 0u ? 16u : 0u;
  for (uint k = 0u; k < n; ++k) total += evf_loss_red[k * 16u];
  return total;
}
