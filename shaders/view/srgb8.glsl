// sRGB-valued float (renders: splat colours are sRGB; the viewer's other images are encoded on
// the host) -> 8-bit byte (clamp to [0, 1], NaN -> 0, round), and the packing of one canvas
// pixel (alpha 255; R and B swapped when bgr != 0).
uint evf_to_byte(float v) {
  v = isnan(v) ? 0.0 : clamp(v, 0.0, 1.0);
  return uint(clamp(floor(v * 255.0 + 0.5), 0.0, 255.0));
}
uint evf_pack_rgb(float r, float g, float b, uint bgr) {
  uint R = evf_to_byte(r), G = evf_to_byte(g), B = evf_to_byte(b);
  if (bgr != 0u) { uint t = R; R = B; B = t; }
  return R | (G << 8) | (B << 16) | (255u << 24);
}
// An rgba word (memory order R,G,B,A) in the canvas's byte order.
uint evf_canvas_rgba(uint rgba, uint bgr) {
  if (bgr == 0u) return rgba;
  return (rgba & 0xFF00FF00u) | ((rgba & 0xFFu) << 16) | ((rgba >> 16) & 0xFFu);
}
