// Element-wise layers' maths, shared by their forward and backward shaders (nn_layout.h,
// PointwisePC). The including shader declares pc.

float nn_relu(float x) { return max(x, 0.0); }
// d relu / dx from the forward's output: 1 where it passed the input on.
float nn_relu_slope(float y) { return y > 0.0 ? 1.0 : 0.0; }

// 1 / (1 + e^-x), written so that neither side overflows to inf / inf.
float nn_sigmoid(float x) {
  float e = exp(-abs(x));
  return x >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
}
float nn_sigmoid_slope(float y) { return y * (1.0 - y); }

// x2 nearest up-sampling: the low-resolution value under output value i (channel-major).
uint nn_upsample_source(uint i) {
  uint out_hw = pc.out_h * pc.out_w, c = i / out_hw, p = i - c * out_hw, y = p / pc.out_w, x = p - y * pc.out_w;
  return (c * pc.in_h + y / 2u) * pc.in_w + x / 2u;
}
