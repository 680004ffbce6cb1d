// Flow-upsampled blur maths shared by train/upsample (forward) and train/upsample_bwd (its exact
// adjoint); train_layout.h, UpsamplePC. The including shader declares flow[] (the view's dx, dy
// planes per interval) and pc.

uint up_hw() { return pc.width * pc.height; }
vec2 up_disp(ivec2 p) {
  uint i = uint(p.y) * pc.width + uint(p.x), base = 2u * pc.interval * up_hw();
  return vec2(flow[base + i], flow[base + up_hw() + i]);
}
bool up_inside(ivec2 p) { return p.x >= 0 && p.y >= 0 && p.x < int(pc.width) && p.y < int(pc.height); }
// Whether tap q of target x counts at fraction s (its warped position is within reach of x).
bool up_tap_in(ivec2 x, ivec2 q, float s) {
  if (!up_inside(q)) return false;
  ivec2 c = q + ivec2(roundEven(s * up_disp(q)));
  ivec2 e = abs(x - c);
  return max(e.x, e.y) <= kUpsampleReach;
}

// Target x's taps at fraction s: the top-left tap and the four bilinear weights with excluded
// taps zeroed, and their sum.
struct UpTaps {
  ivec2 q0;
  vec4 w;  // (q0, q0 + (1,0), q0 + (0,1), q0 + (1,1))
  float total;
};
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
  t.total = t.w.x + t.w.y + t.w.z + t.w.w;
  return t;
}
// The normalised weight of tap q in x's taps (0 when q is not one of them).
float up_weight_of(UpTaps t, ivec2 q) {
  ivec2 d = q - t.q0;
  if (t.total <= 0.0 || d.x < 0 || d.y < 0 || d.x > 1 || d.y > 1) return 0.0;
  float w = d.y == 0 ? (d.x == 0 ? t.w.x : t.w.y) : (d.x == 0 ? t.w.z : t.w.w);
  return w / t.total;
}
