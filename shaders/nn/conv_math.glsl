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

// Pixel n of a w-wide image as (x, y).
uvec2 conv_pixel(uint n, uint w) {
  uint y = n / w;
  return uvec2(n - y * w, y);
}
uvec2 conv_pixel_next(uvec2 p, uint w) { return p.x + 1u == w ? uvec2(0u, p.y + 1u) : uvec2(p.x + 1u, p.y); }

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
