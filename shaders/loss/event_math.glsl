// Event-loss maths shared by loss/event_pair (forward), loss/event_pair_bwd (backward),
// loss/event_pair_value (the value alone) and the warped-event loss (loss/warped_event*).
// Luminance weights match the simulator's event model (engine/events/event_model.h).
const vec3 kEventLuma = vec3(0.2126, 0.7152, 0.0722);

float event_luma(vec3 rgb) { return dot(kEventLuma, rgb); }
// L = log(eps + max(0, Y)); dL/dY = 1 / (eps + Y) where Y > 0, else 0.
float event_log_luma(vec3 rgb, float eps) { return log(eps + max(0.0, event_luma(rgb))); }
vec3 event_log_luma_grad(vec3 rgb, float eps) {
  float y = event_luma(rgb);
  return y > 0.0 ? kEventLuma / (eps + y) : vec3(0.0);
}
// The same for four pixels at once, from their planar channels (the quad kernels' vec4 accesses).
vec4 event_luma(vec4 r, vec4 g, vec4 b) { return kEventLuma.r * r + kEventLuma.g * g + kEventLuma.b * b; }
vec4 event_log_luma(vec4 r, vec4 g, vec4 b, float eps) { return log(eps + max(vec4(0.0), event_luma(r, g, b))); }
// dL/d(channel) of four pixels of luminance y, the channel's weight w: w / (eps + y) where y > 0.
vec4 event_log_luma_grad(vec4 y, float w, float eps) {
  return mix(vec4(0.0), w / (eps + y), greaterThan(y, vec4(0.0)));
}

// Cells of pool x pool pixels along a side of `size` pixels, the last one cut by the border.
uint event_cells(uint size, uint pool) { return (size + pool - 1u) / pool; }

// A pair's norms from its sums ED, DD, EE (norms below the floor are held at it).
float event_norm(float sq, float floor2) { return sqrt(max(sq, floor2)); }
// l = || E/nE - D/nD ||^2 from the sums.
float event_pair_loss(float ed, float dd, float ee, float floor2) {
  float nE = event_norm(ee, floor2), nD = event_norm(dd, floor2);
  return ee / (nE * nE) + dd / (nD * nD) - 2.0 * ed / (nE * nD);
}
// dl/dD at a pixel with values e, d: 2 (d/nD - e/nE) / nD, plus, when nD follows D (not held at
// the floor), the norm's share 2 d (ED/(nE nD) - DD/nD^2) / nD^2. For one pixel (float) or four
// (vec4): one body, defined for both types.
#define EVF_EVENT_PAIR_DL_DD(T)                                                       \
  T event_pair_dl_dd(T e, T d, float ed, float dd, float ee, float floor2) {          \
    float nE = event_norm(ee, floor2), nD = event_norm(dd, floor2);                   \
    T g = 2.0 * (d / nD - e / nE) / nD;                                               \
    if (!(dd < floor2)) g += 2.0 * d * (ed / (nE * nD) - dd / (nD * nD)) / (nD * nD); \
    return g;                                                                         \
  }
EVF_EVENT_PAIR_DL_DD(float)
EVF_EVENT_PAIR_DL_DD(vec4)
