// The sRGB transfer function (IEC 61966-2-1) and its derivatives, extended linearly below the
// knee to negative values (renders can leave [0, 1]; above 1 the power segment continues).
// Splat colours and renders are display-referred sRGB, as in every 3DGS tool; the blur model
// and the event log intensity need linear light, so the trainer decodes renders per pixel.
// Host twins: io::srgb_to_linear / io::linear_to_srgb (engine/io/image.cpp).
float evf_srgb_decode(float x) {
  return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}
float evf_srgb_decode_deriv(float x) {
  return x <= 0.04045 ? 1.0 / 12.92 : (2.4 / 1.055) * pow((x + 0.055) / 1.055, 1.4);
}
// decode'(x) from the decode y = decode(x) alone: above the knee (y > decode(0.04045) =
// 0.04045 / 12.92) decode'(x) = (2.4 / 1.055) y^(1 - 1 / 2.4). Equal to evf_srgb_decode_deriv up to
// rounding.
vec4 evf_srgb_decode_deriv_of_linear(vec4 y) {
  vec4 power = (2.4 / 1.055) * pow(max(y, vec4(1e-30)), vec4(1.4 / 2.4));
  return mix(power, vec4(1.0 / 12.92), lessThanEqual(y, vec4(0.04045 / 12.92)));
}
float evf_srgb_encode(float y) {
  return y <= 0.0031308 ? y * 12.92 : 1.055 * pow(y, 1.0 / 2.4) - 0.055;
}
float evf_srgb_encode_deriv(float y) {
  return y <= 0.0031308 ? 12.92 : (1.055 / 2.4) * pow(y, -1.4 / 2.4);
}
