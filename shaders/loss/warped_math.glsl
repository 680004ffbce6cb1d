// Warped-event loss maths shared by loss/warped_event (forward) and loss/warped_event_bwd
// (loss_layout.h, WarpedEventPC). The including shader declares frame[] (planar RGB of frame
// j), planes[] (the view's M, dx, dy per interval) and pc; event_math.glsl comes first.

// Only interior pixels take part (the central differences need all four neighbours).
bool warped_interior(uint x, uint y) { return x > 0u && y > 0u && x + 1u < pc.width && y + 1u < pc.height; }
uint warped_plane(uint k, uint hw) { return (3u * pc.interval + k) * hw; }
float warped_log_luma(uint p, uint hw) {
  return event_log_luma(vec3(frame[p], frame[hw + p], frame[2u * hw + p]), pc.eps);
}
// P = -(Lx dx + Ly dy) at interior pixel p: the brightness change that the interval's motion
// makes of the frame's log-luminance edges.
float warped_predicted(uint p, uint hw) {
  float lx = 0.5 * (warped_log_luma(p + 1u, hw) - warped_log_luma(p - 1u, hw));
  float ly = 0.5 * (warped_log_luma(p + pc.width, hw) - warped_log_luma(p - pc.width, hw));
  return -(lx * planes[warped_plane(1u, hw) + p] + ly * planes[warped_plane(2u, hw) + p]);
}
