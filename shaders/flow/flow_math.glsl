// The flow estimator's maths, shared by the forward (vote) and the backward (flow_grad) kernels:
// the node grid's bilinear flow, the warp, the bilinear vote and its derivative. Each backward
// function sits under the forward function it differentiates. The C++ double reference in
// engine/flow/flow_reference.cpp follows the same definitions.

// Cell of the node grid under pixel centre coordinate `c` (pixels) on an axis of `size` pixels
// and n tiles: the left node index and the fraction towards the next node.
void flow_cell(float c, uint size, uint n, out uint a, out float f) {
  float g = c * float(n) / float(size);
  float fl = clamp(floor(g), 0.0, float(n - 1u));
  a = uint(fl);
  f = g - fl;
}

// Flow (pixels per interval) of interval j at pixel (x, y): bilinear in the node grid. The
// including shader defines `vec2 flow_node(uint i)` reading node i = j * (n+1)^2 + b * (n+1) + a
// (u, v of node (a, b)) before including this header.
vec2 flow_at(uint j, uint n, uint W, uint H, uint x, uint y) {
  uint a, b;
  float fa, fb;
  flow_cell(float(x) + 0.5, W, n, a, fa);
  flow_cell(float(y) + 0.5, H, n, b, fb);
  uint s = n + 1u, base = j * s * s + b * s + a;
  return (1.0 - fb) * ((1.0 - fa) * flow_node(base) + fa * flow_node(base + 1u)) +
         fb * ((1.0 - fa) * flow_node(base + s) + fa * flow_node(base + s + 1u));
}

// Reference time r (normalised exposure time): start, middle, end.
float flow_ref_time(uint r) { return 0.5 * float(r); }

// The flow is piecewise constant in time, so the position of a pixel's content at time t,
// relative to where it is at the first frame time, is P(t) = C_i + f (C_{i+1} - C_i), with
// C_j = u_0 + ... + u_{j-1} the cumulative flow at frame j, i the interval holding t and f the
// fraction of it that has passed (t before the first frame: P = C_0 = 0; after the last: C_J).
// An event moves from t_k to t_r by P(t_r) - P(t_k) = sum_j lever_j u_j, lever_j the signed part
// of [t_k, t_r] inside interval j in interval lengths. The intervals are (start, end, 1 / length)
// in the including shader's `intervals` buffer (it defines FLOW_INTERVALS); `i` is advanced from
// where it is (a pixel's events come in time order).
#ifdef FLOW_INTERVALS
float flow_interval_fraction(float t, uint count, inout uint i) {
  while (i + 1u < count && t >= intervals[i].y) ++i;
  return clamp((t - intervals[i].x) * intervals[i].z, 0.0, 1.0);
}
// The event kernels walk a pixel's events in time order; interval j of `count` takes the events
// before this time (the last takes the rest), as flow_interval_fraction assigns them. They keep
// the current interval's cumulative flows in registers (read from flow/positions' output): no
// array indexed by a per-invocation interval (the CPU driver turns those into chains of selects).
// The interval of time t, as flow_interval_fraction finds it, by a loop every invocation runs alike.
uint flow_event_interval(float t, uint count) {
  uint i = 0u;
  for (uint j = 0u; j + 1u < count; ++j) i += t >= intervals[j].y ? 1u : 0u;
  return i;
}
float flow_interval_end(uint j, uint count) { return j + 1u < count ? intervals[j].y : 3.0e38; }

#endif

// Bilinear footprint of a point q (pixel coordinates, centres at +0.5): the top-left pixel and
// the fractions. Votes: (1-fx)(1-fy), fx(1-fy), (1-fx)fy, fx fy.
void flow_footprint(vec2 q, out ivec2 i0, out vec2 f) {
  vec2 g = q - 0.5;
  vec2 fl = floor(g);
  i0 = ivec2(fl);
  f = g - fl;
}
// d(sum_k A_k w_k) / dq for the four corner values A00, A10, A01, A11.
vec2 flow_footprint_grad(vec2 f, float a00, float a10, float a01, float a11) {
  return vec2((1.0 - f.y) * (a10 - a00) + f.y * (a11 - a01), (1.0 - f.x) * (a01 - a00) + f.x * (a11 - a10));
}

// Tap d (|d| <= kFlowBlurRadius) of the Gaussian of standard deviation kFlowBlurSigma, normalised
// to sum 1 over the taps.
float flow_gauss(int d) {
  float sum = 0.0;
  for (int k = -kFlowBlurRadius; k <= kFlowBlurRadius; ++k) sum += exp(-0.5 * float(k * k) / (kFlowBlurSigma * kFlowBlurSigma));
  return exp(-0.5 * float(d * d) / (kFlowBlurSigma * kFlowBlurSigma)) / sum;
}
