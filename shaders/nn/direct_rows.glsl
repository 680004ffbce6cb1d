// The direct 3x3 convolutions' input rows (nn_layout.h), shared by nn/conv3x3_direct and
// nn/conv3x3_direct_dw. The including shader declares pc (with h, w) and the input buffer x: vec4s
// (rows of whole vec4s, w % 4 == 0) or, with EVF_DIRECT_ANY_WIDTH, floats.

// The build's block rows and channel group (nn_layout.h): EVF_DIRECT_CHECKED selects the small
// geometry of the "_checked" builds.
#ifdef EVF_DIRECT_CHECKED
const uint kRows = kDirectRowsChecked, kGroup = kDirectGroupChecked;
#else
const uint kRows = kDirectRows, kGroup = kDirectGroup;
#endif

// Input row iy of channel plane `plane` around columns [x0, x0 + 4): the row's 4 values shifted by
// -1, 0 and +1 pixels (the taps kx = 0, 1, 2), zeros outside the image.
#ifdef EVF_DIRECT_ANY_WIDTH
void load_row(uint plane, int iy, uint x0, out vec4 taps[3]) {
  bool row_in = iy >= 0 && iy < int(pc.h);
  uint row = (plane * pc.h + uint(clamp(iy, 0, int(pc.h) - 1))) * pc.w;
  float v[6];  // columns x0 - 1 .. x0 + 4
  [[unroll]] for (uint k = 0u; k < 6u; ++k) {
    int ix = int(x0 + k) - 1;
    v[k] = row_in && ix >= 0 && ix < int(pc.w) ? x[row + uint(clamp(ix, 0, int(pc.w) - 1))] : 0.0;
  }
  taps[0] = vec4(v[0], v[1], v[2], v[3]);
  taps[1] = vec4(v[1], v[2], v[3], v[4]);
  taps[2] = vec4(v[2], v[3], v[4], v[5]);
}
#else
void load_row(uint plane, int iy, uint x0, out vec4 taps[3]) {
  bool row_in = iy >= 0 && iy < int(pc.h);
  uint q = (plane * pc.h + uint(clamp(iy, 0, int(pc.h) - 1))) * (pc.w / 4u) + x0 / 4u;
  vec4 mid = row_in ? x[q] : vec4(0.0);
  float left = row_in && x0 > 0u ? x[q - (x0 > 0u ? 1u : 0u)].w : 0.0;
  float right = row_in && x0 + 4u < pc.w ? x[q + (x0 + 4u < pc.w ? 1u : 0u)].x : 0.0;
  taps[0] = vec4(left, mid.xyz);
  taps[1] = mid;
  taps[2] = vec4(mid.yzw, right);
}
#endif
