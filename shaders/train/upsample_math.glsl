// Flow-upsampled blur maths shared by train/upsample_taps (the taps, once per step),
// train/upsample (forward) and train/upsample_bwd (its exact adjoint); train_layout.h,
// UpsamplePC. The including shader declares pc and, where it reads the flow, flow[] (the
// view's dx, dy planes per interval, EVF_UPSAMPLE_FLOW defined) and, where it reads taps,
// taps[] (EVF_UPSAMPLE_TAPS defined).

uint up_hw() { return pc.width * pc.height; }
bool up_inside(ivec2 p) { return p.x >= 0 && p.y >= 0 && p.x < int(pc.width) && p.y < int(pc.height); }

#ifdef EVF_UPSAMPLE_FLOW
vec2 up_disp(ivec2 p) {
  uint i = uint(p.y) * pc.width + uint(p.x), base = 2u * pc.interval * up_hw();
  return vec2(flow[base + i], flow[base + up_hw() + i]);
}
// Where q's own warped position lands at fraction s: the centre of the square its targets lie in.
ivec2 up_centre(ivec2 q, float s) { return q + ivec2(roundEven(s * up_disp(q))); }
// Whether tap q of target x counts at fraction s (its warped position is within reach of x).
bool up_tap_in(ivec2 x, ivec2 q, float s) {
  if (!up_inside(q)) return false;
  ivec2 e = abs(x - up_centre(q, s));
  return max(e.x, e.y) <= kUpsampleReach;
}
#endif

// Target x's taps at one fraction: the top-left tap and the four bilinear weights (q0, q0 + (1,0),
// q0 + (0,1), q0 + (1,1)) with excluded taps zeroed, normalised; all 0 when none is left.
struct UpTaps {
  ivec2 q0;
  vec4 w;
};

#ifdef EVF_UPSAMPLE_FLOW
UpTaps up_taps(ivec2 x, float s) {
  vec2 p = vec2(x) - s * up_disp(x);
  vec2 f = floor(p), a = p - f;
  UpTaps t;
  t.q0 = ivec2(f);
  t.w = vec4((1.0 - a.x) * (1.0 - a.y), a.x * (1.0 - a.y), (1.0 - a.x) * a.y, a.x * a.y);
  if (!up_tap_in(x, t.q0, s)) t.w.x = 0.0;
  if (!up_tap_in(x, t.q0 + ivec2(1, 0), s)) t.w.y = 0.0;
  if (!up_tap_in(x, t.q0 + ivec2(0, 1), s)) t.w.z = 0.0;
  if (!up_tap_in(x, t.q0 + ivec2(1, 1), s)) t.w.w = 0.0;
  float total = t.w.x + t.w.y + t.w.z + t.w.w;
  t.w = total > 0.0 ? t.w / total : vec4(0.0);
  return t;
}
#endif

#ifdef EVF_UPSAMPLE_TAPS
// Entry of sub-frame m (1..M-1) of the interval at pixel index i.
uint up_entry(uint m, uint i) {
  return ((pc.interval * (pc.upsample - 1u) + m - 1u) * up_hw() + i) * kUpsampleTapFloats;
}
UpTaps up_load(uint m, uint i) {
  uint e = up_entry(m, i);
  UpTaps t;
  t.q0 = ivec2(floatBitsToInt(taps[e]), floatBitsToInt(taps[e + 1u]));
  t.w = vec4(taps[e + 2u], taps[e + 3u], taps[e + 4u], taps[e + 5u]);
  return t;
}
// The weight of tap q in t (0 when q is not one of them).
float up_weight_of(UpTaps t, ivec2 q) {
  ivec2 d = q - t.q0;
  if (d.x < 0 || d.y < 0 || d.x > 1 || d.y > 1) return 0.0;
  return d.y == 0 ? (d.x == 0 ? t.w.x : t.w.y) : (d.x == 0 ? t.w.z : t.w.w);
}
bool up_no_tap(UpTaps t) { return t.w == vec4(0.0); }
#endif
