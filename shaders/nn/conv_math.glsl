// Index maths of the convolutions, shared by the forward and both backward passes (nn_layout.h,
// ConvPC). The including shader declares pc.

// Row k of the unrolled kernel: channel k / (K * K) and tap (ky, kx), as the offset of the tap's
// input pixel from the output pixel's stride-scaled position, (ky - pad, kx - pad).
struct ConvTap {
  uint c;
  ivec2 d;  // (x, y) offset
};
ConvTap conv_tap(uint k) {
  uint taps = pc.ksize * pc.ksize, c = k / taps, t = k - c * taps, ky = t / pc.ksize;
  return ConvTap(c, ivec2(int(t - ky * pc.ksize), int(ky)) - int(pc.pad));
}
// The next row's tap (k + 1), stepping without divisions.
ConvTap conv_tap_next(ConvTap t) {
  t.d.x += 1;
  if (t.d.x > int(pc.pad)) {
    t.d.x = -int(pc.pad);
    t.d.y += 1;
    if (t.d.y > int(pc.pad)) {
      t.d.y = -int(pc.pad);
      t.c += 1u;
    }
  }
  return t;
}

// Pixel n of a batch of w x h images as (x, y, image).
uvec3 conv_pixel(uint n, uint w, uint h) {
  uint hw = w * h, b = n / hw, r = n - b * hw, y = r / w;
  return uvec3(r - y * w, y, b);
}
uvec3 conv_pixel_next(uvec3 p, uint w, uint h) {
  if (p.x + 1u < w) return uvec3(p.x + 1u, p.y, p.z);
  return p.y + 1u < h ? uvec3(0u, p.y + 1u, p.z) : uvec3(0u, 0u, p.z + 1u);
}
// The element of channel c at pixel p (x, y, image) of a batch of c_count-channel w x h images.
uint conv_element(uint c, uvec2 xy, uint b, uint c_count, uint h, uint w) { return ((b * c_count + c) * h + xy.y) * w + xy.x; }
// The element of channel c at the n-th batch pixel (conv_pixel's n), images of hw pixels.
uint conv_plane_element(uint c, uint n, uint c_count, uint hw) { return n + ((n / hw) * (c_count - 1u) + c) * hw; }

// The input pixel that tap t of output pixel o reads (may lie outside the input).
ivec2 conv_input_pixel(uvec2 o, ConvTap t) { return ivec2(o * pc.stride) + t.d; }
bool conv_inside_input(ivec2 p) { return p.x >= 0 && p.y >= 0 && p.x < int(pc.in_w) && p.y < int(pc.in_h); }

// The output pixel whose tap t reads input pixel i, if any (the adjoint of conv_input_pixel).
bool conv_output_of(ivec2 i, ConvTap t, out uvec2 o) {
  ivec2 s = i - t.d;
  if (s.x < 0 || s.y < 0) return false;
  uvec2 u = uvec2(s);
  o = u / pc.stride;
  return all(equal(o * pc.stride, u)) && o.x < pc.out_w && o.y < pc.out_h;
}
