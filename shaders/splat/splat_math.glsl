// The maths of the splat rasterizer, forward and backward side by side (docs/rasterizer.md).
// Every backward function is the vector-Jacobian product of the forward function above it.
// Matrices: GLSL mat3 is column-major; m[c][r]. We build them from rows with transpose().

const float kAlphaMin = 1.0 / 255.0;
const float kAlphaMax = 0.99;
const float kTransmittanceMin = 1e-4;
const float kDilation = 0.3;
const float kBoxPad = 1e-3;

// ---------------------------------------------------------------- quaternion -> rotation
mat3 quat_to_rotmat(vec4 q) {  // q = (w, x, y, z), unit
  float w = q.x, x = q.y, y = q.z, z = q.w;
  return transpose(mat3(1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
                        2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
                        2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)));
}
// v_R: gradient w.r.t. the matrix entries; returns the gradient w.r.t. the unit quaternion.
vec4 quat_to_rotmat_vjp(vec4 q, mat3 v_R) {
  float w = q.x, x = q.y, y = q.z, z = q.w;
  // G[r][c] = v_R[c][r]
  float g00 = v_R[0][0], g01 = v_R[1][0], g02 = v_R[2][0];
  float g10 = v_R[0][1], g11 = v_R[1][1], g12 = v_R[2][1];
  float g20 = v_R[0][2], g21 = v_R[1][2], g22 = v_R[2][2];
  return 2.0 * vec4(-z * g01 + y * g02 + z * g10 - x * g12 - y * g20 + x * g21,
                    y * g01 + z * g02 + y * g10 - 2.0 * x * g11 - w * g12 + z * g20 + w * g21 - 2.0 * x * g22,
                    -2.0 * y * g00 + x * g01 + w * g02 + x * g10 + z * g12 - w * g20 + z * g21 - 2.0 * y * g22,
                    -2.0 * z * g00 - w * g01 + x * g02 + w * g10 - 2.0 * z * g11 + y * g12 + x * g20 + y * g21);
}
// Normalisation q/|q| and its VJP.
vec4 normalize_vjp(vec4 q, vec4 v_qn) {
  float inv = inversesqrt(dot(q, q));
  vec4 qn = q * inv;
  return (v_qn - qn * dot(qn, v_qn)) * inv;
}

// ---------------------------------------------------------------- spherical harmonics
const float SH_C0 = 0.28209479177387814;
const float SH_C1 = 0.4886025119029199;
const float SH_C2[5] = float[5](1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792,
                                0.5462742152960396);
const float SH_C3[7] = float[7](-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
                                -0.4570457994644658, 1.445305721320277, -0.5900435899266435);

// Basis values Y_k(d) for k < (degree+1)^2 (zero beyond).
void sh_basis(vec3 d, uint degree, out float Y[16]) {
  for (int k = 0; k < 16; ++k) Y[k] = 0.0;
  float x = d.x, y = d.y, z = d.z;
  Y[0] = SH_C0;
  if (degree < 1) return;
  Y[1] = -SH_C1 * y; Y[2] = SH_C1 * z; Y[3] = -SH_C1 * x;
  if (degree < 2) return;
  float xx = x * x, yy = y * y, zz = z * z;
  Y[4] = SH_C2[0] * x * y; Y[5] = SH_C2[1] * y * z; Y[6] = SH_C2[2] * (2.0 * zz - xx - yy);
  Y[7] = SH_C2[3] * x * z; Y[8] = SH_C2[4] * (xx - yy);
  if (degree < 3) return;
  Y[9] = SH_C3[0] * y * (3.0 * xx - yy); Y[10] = SH_C3[1] * x * y * z; Y[11] = SH_C3[2] * y * (4.0 * zz - xx - yy);
  Y[12] = SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy); Y[13] = SH_C3[4] * x * (4.0 * zz - xx - yy);
  Y[14] = SH_C3[5] * z * (xx - yy); Y[15] = SH_C3[6] * x * (xx - 3.0 * yy);
}
// sum_k w[k] * grad Y_k(d): the VJP of the basis with respect to the direction.
vec3 sh_basis_vjp(vec3 d, uint degree, float w[16]) {
  vec3 g = vec3(0.0);
  if (degree < 1) return g;
  float x = d.x, y = d.y, z = d.z;
  g += vec3(-SH_C1 * w[3], -SH_C1 * w[1], SH_C1 * w[2]);
  if (degree < 2) return g;
  float xx = x * x, yy = y * y, zz = z * z;
  g += w[4] * SH_C2[0] * vec3(y, x, 0.0);
  g += w[5] * SH_C2[1] * vec3(0.0, z, y);
  g += w[6] * SH_C2[2] * vec3(-2.0 * x, -2.0 * y, 4.0 * z);
  g += w[7] * SH_C2[3] * vec3(z, 0.0, x);
  g += w[8] * SH_C2[4] * vec3(2.0 * x, -2.0 * y, 0.0);
  if (degree < 3) return g;
  g += w[9] * SH_C3[0] * vec3(6.0 * x * y, 3.0 * xx - 3.0 * yy, 0.0);
  g += w[10] * SH_C3[1] * vec3(y * z, x * z, x * y);
  g += w[11] * SH_C3[2] * vec3(-2.0 * x * y, 4.0 * zz - xx - 3.0 * yy, 8.0 * y * z);
  g += w[12] * SH_C3[3] * vec3(-6.0 * x * z, -6.0 * y * z, 6.0 * zz - 3.0 * xx - 3.0 * yy);
  g += w[13] * SH_C3[4] * vec3(4.0 * zz - 3.0 * xx - yy, -2.0 * x * y, 8.0 * x * z);
  g += w[14] * SH_C3[5] * vec3(2.0 * x * z, -2.0 * y * z, xx - yy);
  g += w[15] * SH_C3[6] * vec3(3.0 * xx - 3.0 * yy, -6.0 * x * y, 0.0);
  return g;
}

// ---------------------------------------------------------------- projection
struct Camera {
  mat3 R;       // world -> camera rotation
  vec3 t;
  vec4 intrin;  // fx fy cx cy
  vec2 size;    // W H
};

// Clamped EWA Jacobian (Inria): u, v are clamped to 1.3 x the half field of view.
mat3x2 ewa_jacobian(vec3 p, Camera cam) {
  float fx = cam.intrin.x, fy = cam.intrin.y;
  vec2 lim = 1.3 * 0.5 * cam.size / cam.intrin.xy;
  float u = clamp(p.x / p.z, -lim.x, lim.x), v = clamp(p.y / p.z, -lim.y, lim.y);
  // mat3x2: 3 columns of vec2; J[col][row]
  return mat3x2(vec2(fx / p.z, 0.0), vec2(0.0, fy / p.z), vec2(-fx * u / p.z, -fy * v / p.z));
}
vec3 ewa_jacobian_vjp(vec3 p, Camera cam, mat3x2 v_J) {
  float fx = cam.intrin.x, fy = cam.intrin.y;
  vec2 lim = 1.3 * 0.5 * cam.size / cam.intrin.xy;
  float z = p.z, iz = 1.0 / z, iz2 = iz * iz;
  float ru = p.x / z, rv = p.y / z;
  vec3 v_p = vec3(0.0);
  v_p.z += -fx * iz2 * v_J[0][0] - fy * iz2 * v_J[1][1];
  // J02 = -fx u / z
  if (ru > -lim.x && ru < lim.x) {  // u = x / z:  J02 = -fx x / z^2
    v_p.x += -fx * iz2 * v_J[2][0];
    v_p.z += 2.0 * fx * p.x * iz2 * iz * v_J[2][0];
  } else {
    v_p.z += fx * clamp(ru, -lim.x, lim.x) * iz2 * v_J[2][0];
  }
  if (rv > -lim.y && rv < lim.y) {
    v_p.y += -fy * iz2 * v_J[2][1];
    v_p.z += 2.0 * fy * p.y * iz2 * iz * v_J[2][1];
  } else {
    v_p.z += fy * clamp(rv, -lim.y, lim.y) * iz2 * v_J[2][1];
  }
  return v_p;
}

// Opacity compensation of the antialiased mode: sqrt(det(S2) / det(S2 + 0.3 I)).
float aa_compensation(vec3 cov2d) {
  float det = cov2d.x * cov2d.z - cov2d.y * cov2d.y;
  float detd = (cov2d.x + kDilation) * (cov2d.z + kDilation) - cov2d.y * cov2d.y;
  return sqrt(max(0.0, det / detd));
}
vec3 aa_compensation_vjp(vec3 cov2d, float v_comp) {
  float a = cov2d.x, b = cov2d.y, c = cov2d.z;
  float det = a * c - b * b;
  float ad = a + kDilation, cd = c + kDilation;
  float detd = ad * cd - b * b;
  float r = det / detd;
  if (r <= 0.0) return vec3(0.0);
  float v_r = v_comp * 0.5 / sqrt(r);
  float inv2 = 1.0 / (detd * detd);
  return v_r * vec3((c * detd - det * cd) * inv2, (-2.0 * b * detd + 2.0 * b * det) * inv2,
                    (a * detd - det * ad) * inv2);
}

// Conic (inverse of the dilated 2-D covariance) and its VJP. cov2d = (a, b, c) undilated.
vec3 conic_of(vec3 cov2d) {
  float ad = cov2d.x + kDilation, cd = cov2d.z + kDilation, b = cov2d.y;
  float D = ad * cd - b * b;
  return vec3(cd / D, -b / D, ad / D);
}
vec3 conic_vjp(vec3 cov2d, vec3 v_conic) {
  float ad = cov2d.x + kDilation, cd = cov2d.z + kDilation, b = cov2d.y;
  float D = ad * cd - b * b, iD = 1.0 / D, iD2 = iD * iD;
  float v_a = v_conic.x * (-cd * cd * iD2) + v_conic.y * (b * cd * iD2) + v_conic.z * (iD - ad * cd * iD2);
  float v_c = v_conic.x * (iD - cd * ad * iD2) + v_conic.y * (b * ad * iD2) + v_conic.z * (-ad * ad * iD2);
  float v_b = v_conic.x * (2.0 * b * cd * iD2) + v_conic.y * (-iD - 2.0 * b * b * iD2) + v_conic.z * (2.0 * b * ad * iD2);
  return vec3(v_a, v_b, v_c);
}

// 3-D covariance from log-scales and a unit quaternion: S = M M^T, M = Rq diag(exp(ls)).
mat3 covariance_3d(vec3 log_scale, vec4 qn) {
  mat3 M = quat_to_rotmat(qn) * mat3(vec3(exp(log_scale.x), 0, 0), vec3(0, exp(log_scale.y), 0), vec3(0, 0, exp(log_scale.z)));
  return M * transpose(M);
}
// v_Sigma symmetric. Outputs the gradients w.r.t. log-scales and the unit quaternion.
void covariance_3d_vjp(vec3 log_scale, vec4 qn, mat3 v_Sigma, out vec3 v_log_scale, out vec4 v_qn) {
  mat3 Rq = quat_to_rotmat(qn);
  vec3 s = exp(log_scale);
  mat3 M = Rq * mat3(vec3(s.x, 0, 0), vec3(0, s.y, 0), vec3(0, 0, s.z));
  mat3 v_M = 2.0 * v_Sigma * M;
  // M[:, i] = Rq[:, i] * s_i
  mat3 v_Rq = mat3(v_M[0] * s.x, v_M[1] * s.y, v_M[2] * s.z);
  vec3 v_s = vec3(dot(Rq[0], v_M[0]), dot(Rq[1], v_M[1]), dot(Rq[2], v_M[2]));
  v_log_scale = v_s * s;
  v_qn = quat_to_rotmat_vjp(qn, v_Rq);
}

// Axis-aligned half extents of the support {d : d^T conic d <= q_max}, padded.
vec2 support_extent(vec3 cov2d, float q_max) {
  return sqrt(q_max * vec2(cov2d.x + kDilation, cov2d.z + kDilation)) * (1.0 + kBoxPad) + 1e-4;
}

// A Gaussian's tile rectangle [t0, t1) (16 bits a coordinate: the host checks the tile grid) and
// which of its first 32 tiles, row by row, the support meets (project.comp tests each tile once;
// emit.comp lists rectangles of up to kTileMaskTiles tiles from the mask without testing again).
const uint kTileMaskTiles = 32u;
uvec4 tile_rect_pack(uvec2 t0, uvec2 t1, uint mask) { return uvec4(t0.x | (t0.y << 16u), t1.x | (t1.y << 16u), mask, 0u); }
void tile_rect_unpack(uvec4 r, out uvec2 t0, out uvec2 t1, out uint mask) {
  t0 = uvec2(r.x & 0xFFFFu, r.x >> 16u);
  t1 = uvec2(r.y & 0xFFFFu, r.y >> 16u);
  mask = r.z;
}

// Does the support ellipse meet the rectangle [lo, hi] (pixel centres)? Exact: minimum of the
// quadratic form over the rectangle, found on its edges when the mean is outside.
bool ellipse_meets_rect(vec2 mean, vec3 conic, float q_max, vec2 lo, vec2 hi) {
  if (all(greaterThanEqual(mean, lo)) && all(lessThanEqual(mean, hi))) return true;
  float qlim = q_max * (1.0 + 2.0 * kBoxPad);
  float best = 1e30;
  // Vertical edges x = lo.x, hi.x: q(dx, dy) minimised over dy.
  for (int e = 0; e < 2; ++e) {
    float dx = (e == 0 ? lo.x : hi.x) - mean.x;
    float dy = clamp(-conic.y * dx / conic.z, lo.y - mean.y, hi.y - mean.y);
    best = min(best, conic.x * dx * dx + 2.0 * conic.y * dx * dy + conic.z * dy * dy);
    float dy2 = (e == 0 ? lo.y : hi.y) - mean.y;
    float dx2 = clamp(-conic.y * dy2 / conic.x, lo.x - mean.x, hi.x - mean.x);
    best = min(best, conic.x * dx2 * dx2 + 2.0 * conic.y * dx2 * dy2 + conic.z * dy2 * dy2);
  }
  return best <= qlim;
}

// ---------------------------------------------------------------- compositing
// Gaussian weight exp(-q/2) at pixel offset d = mean - centre.
float splat_power(vec3 conic, vec2 d) {
  return -0.5 * (conic.x * d.x * d.x + conic.z * d.y * d.y) - conic.y * d.x * d.y;
}

// exp(power) over a block of 4 x 4 pixels (the block kernels) from six exponentials, not one a
// pixel: with dx = dxm + a, dy = dm + b (dxm, dm: mean minus the block's middle; a, b in
// {1.5, 0.5, -0.5, -1.5} for columns 0..3 and rows 0..3), the exponent is the quadratic
// power(dxm, dm) + a px + b py - (conic.x a^2 + conic.z b^2) / 2 - conic.y a b, px and py its
// slopes at the middle. So pixel (a, b) is exp(power(dxm, dm)) times ux^(2a) exp(-conic.x a^2 / 2)
// times uy^(2b) exp(-conic.z b^2 / 2) times w^(4ab), with ux = exp(px / 2), uy = exp(py / 2),
// w = exp(-conic.y / 4): a column factor, a row factor and a cross factor, all worked out once a
// visit. Safe and exact where it matters: |grad power| <= sqrt(2 lambda |power|) for a quadratic
// form whose largest eigenvalue is lambda <= 1 / kDilation (the conic of a dilated covariance). So
// with power(dxm, dm) < kBlockExpFloor no pixel within 1.5 of the middle in x and y reaches power
// >= -ln 255, which alpha >= 1/255 needs (opacity <= 1): the sixteen are then zero. Above the
// floor |px / 2|, |py / 2| <= 7.1, the clamps never act and nothing overflows; below it the clamps
// keep zero times the factors finite (the middle's exponential is taken into the row factor first).
// e_i: row i (dy = dm + 1.5 - i), its components columns 0..3 (dx = dxm + 1.5 - k).
const float kBlockExpFloor = -30.0;
void block_exp(vec3 conic, float dxm, float dm, out vec4 e0, out vec4 e1, out vec4 e2, out vec4 e3) {
  float pm = -0.5 * (conic.x * dxm * dxm + conic.z * dm * dm) - conic.y * dxm * dm;
  float em = pm >= kBlockExpFloor ? exp(pm) : 0.0;
  float ux = exp(clamp(-0.5 * (conic.x * dxm + conic.y * dm), -20.0, 20.0)), vx = 1.0 / ux;
  float uy = exp(clamp(-0.5 * (conic.z * dm + conic.y * dxm), -20.0, 20.0)), vy = 1.0 / uy;
  float kx = exp(-0.125 * conic.x), kx2 = kx * kx, kx4 = kx2 * kx2, kx9 = (kx4 * kx4) * kx;
  float ky = exp(-0.125 * conic.z), ky2 = ky * ky, ky4 = ky2 * ky2, ky9 = (ky4 * ky4) * ky;
  float w1 = exp(-0.25 * conic.y), v1 = 1.0 / w1, w3 = (w1 * w1) * w1, v3 = (v1 * v1) * v1;
  float w9 = (w3 * w3) * w3, v9 = (v3 * v3) * v3;
  vec4 col = vec4((ux * ux) * (ux * kx9), ux * kx, vx * kx, (vx * vx) * (vx * kx9));
  float far = em * ky9, near = em * ky;
  e0 = (col * vec4(w9, w3, v3, v9)) * ((far * uy) * (uy * uy));
  e1 = (col * vec4(w3, w1, v1, v3)) * (near * uy);
  e2 = (col * vec4(v3, v1, w1, w3)) * (near * vy);
  e3 = (col * vec4(v9, v3, w3, w9)) * ((far * vy) * (vy * vy));
}
