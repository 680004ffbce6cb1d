// Event-loss maths shared by loss/event_pair (forward) and loss/event_pair_bwd (backward).
// Luminance weights match the simulator's event model (engine/events/event_model.h).
const vec3 kEventLuma = vec3(0.2126, 0.7152, 0.0722);

float event_luma(vec3 rgb) { return dot(kEventLuma, rgb); }
// L = log(eps + max(0, Y)); dL/dY = 1 / (eps + Y) where Y > 0, else 0.
float event_log_luma(vec3 rgb, float eps) { return log(eps + max(0.0, event_luma(rgb))); }
vec3 event_log_luma_grad(vec3 rgb, float eps) {
  float y = event_luma(rgb);
  return y > 0.0 ? kEventLuma / (eps + y) : vec3(0.0);
}
