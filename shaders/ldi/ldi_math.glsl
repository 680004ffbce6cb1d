// The LDI's double integral and sharp frame (ldi_layout.h, LdiCombinePC), shared by
// ldi/combine and ldi/combine_bwd; each backward function sits under the function it
// differentiates.

// log(1 + e^x), written so that neither e^x overflows nor small values round to 0 early.
float ldi_softplus(float x) { return max(x, 0.0) + log(1.0 + exp(-abs(x))); }
// d softplus / dx = 1 / (1 + e^-x).
float ldi_softplus_slope(float x) {
  float e = exp(-abs(x));
  return x >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
}

// E = softplus(w1 a + w2 b) + kLdiFloor: positive for any a, b.
float ldi_integral(float a, float b) { return ldi_softplus(pc.w1 * a + pc.w2 * b) + kLdiFloor; }
// d/dx of whatever reaches E with gradient g_e, x = w1 a + w2 b.
float ldi_integral_bwd(float a, float b, float g_e) { return g_e * ldi_softplus_slope(pc.w1 * a + pc.w2 * b); }

// A channel of the sharp frame: C = B / E.
float ldi_frame(float blurry, float e) { return blurry / e; }
// d/dE of C's gradient g_c: -g_c B / E^2.
float ldi_frame_bwd(float blurry, float e, float g_c) { return -g_c * blurry / (e * e); }

// The pre-fit's regression to the target integral D: (log E - log D)^2, and its d/dE.
float ldi_log_error(float e, float target) { return log(e) - log(target); }
float ldi_regression_bwd(float e, float target) { return 2.0 * ldi_log_error(e, target) / e; }
