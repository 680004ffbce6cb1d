// The tiled implicit GEMM of the convolutions (nn_layout.h): C[m][n] = sum over k of A(m, k) B(k, n).
// The including shader declares pc (ConvPC) and, before including this file:
//   vec4 gemm_load_a(uint m, uint k)  A(m .. m+3, k), 0 where m >= gemm_m or k >= gemm_k
//   vec4 gemm_load_b(uint k, uint n)  B(k, n .. n+3), 0 where k >= gemm_k or n >= gemm_n
//   void gemm_store(uint m, uint n, float c)
// Each k step of a tile is staged in shared memory once (vec4 entries: four rows of A or four
// columns of B), then every invocation reads its kThreadM values of A and kThreadN of B from it
// and updates its kThreadM x kThreadN sums, in the same order for every run (no atomics).
#extension GL_EXT_control_flow_attributes : require

#if defined(EVF_GEMM_TINY)
const uint kThreadM = kGemmTinyThreadM, kTileM = kGemmTinyTileM, kTileN = kGemmTinyTileN, kThreadN = kGemmThreadN;
#elif defined(EVF_GEMM_NARROW)
const uint kThreadM = kGemmNarrowThreadM, kTileM = kGemmNarrowTileM, kTileN = kGemmNarrowTileN,
           kThreadN = kGemmNarrowThreadN;
#else
const uint kThreadM = kGemmThreadM, kTileM = kGemmTileM, kTileN = kGemmTileN, kThreadN = kGemmThreadN;
#endif
const uint kTileK = kGemmTileK;
const uint kWorkersN = kTileN / kThreadN, kThreads = (kTileM / kThreadM) * kWorkersN;
const uint kQuadsM = kTileM / 4u, kQuadsN = kTileN / 4u;
layout(local_size_x = kThreads) in;

// An invocation's kThreadM x kThreadN sums, its first row m and column n, stored inside the matrix.
void gemm_store_tile(uint m, uint n, vec4 acc[kThreadM][kThreadN / 4u]) {
  [[unroll]] for (uint i = 0u; i < kThreadM; ++i)
    [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q)
      [[unroll]] for (uint j = 0u; j < 4u; ++j)
        if (m + i < pc.gemm_m && n + 4u * q + j < pc.gemm_n) gemm_store(m + i, n + 4u * q + j, acc[i][q][j]);
}

#if defined(EVF_GEMM_TINY)
// At most four rows: each value of B is used by one invocation only, so staging it in shared
// memory would buy nothing and cost two barriers per step of k. Every invocation reads its A and
// B values straight from the buffers, k by k.
void gemm_tile(uint m0, uint n0, uint k_begin, uint k_end) {
  uint tn = gl_LocalInvocationIndex % kWorkersN;
  vec4 acc[kThreadM][kThreadN / 4u];
  [[unroll]] for (uint i = 0u; i < kThreadM; ++i)
    [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q) acc[i][q] = vec4(0.0);
  for (uint k = k_begin; k < min(k_end, pc.gemm_k); ++k) {
    vec4 a = gemm_load_a(m0, k);
    [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q) {
      vec4 b = gemm_load_b(k, n0 + tn * kThreadN + 4u * q);
      [[unroll]] for (uint i = 0u; i < kThreadM; ++i) acc[i][q] = fma(vec4(a[i]), b, acc[i][q]);
    }
  }
  gemm_store_tile(m0, n0 + tn * kThreadN, acc);
}
#else
shared vec4 a_tile[kTileK * kQuadsM];  // [k][m / 4]
shared vec4 b_tile[kTileK * kQuadsN];  // [k][n / 4]

void gemm_stage(uint m0, uint n0, uint k0, uint tid) {
  for (uint v = tid; v < kTileK * kQuadsM; v += kThreads) a_tile[v] = gemm_load_a(m0 + 4u * (v % kQuadsM), k0 + v / kQuadsM);
  for (uint v = tid; v < kTileK * kQuadsN; v += kThreads) b_tile[v] = gemm_load_b(k0 + v / kQuadsN, n0 + 4u * (v % kQuadsN));
}

// The tile at (m0, n0) over k in [k_begin, k_end) (k_end - k_begin a multiple of kTileK, or the
// last chunk, which the loads end at gemm_k), then stored. Called by every invocation of the group.
void gemm_tile(uint m0, uint n0, uint k_begin, uint k_end) {
  uint tid = gl_LocalInvocationIndex, tn = tid % kWorkersN, tm = tid / kWorkersN;
  vec4 acc[kThreadM][kThreadN / 4u];
  [[unroll]] for (uint i = 0u; i < kThreadM; ++i)
    [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q) acc[i][q] = vec4(0.0);
  for (uint k0 = k_begin; k0 < k_end; k0 += kTileK) {
    gemm_stage(m0, n0, k0, tid);
    barrier();
    for (uint kk = 0u; kk < kTileK; ++kk) {
      vec4 a[kThreadM / 4u], b[kThreadN / 4u];
      [[unroll]] for (uint q = 0u; q < kThreadM / 4u; ++q) a[q] = a_tile[kk * kQuadsM + tm * (kThreadM / 4u) + q];
      [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q) b[q] = b_tile[kk * kQuadsN + tn * (kThreadN / 4u) + q];
      [[unroll]] for (uint i = 0u; i < kThreadM; ++i)
        [[unroll]] for (uint q = 0u; q < kThreadN / 4u; ++q) acc[i][q] = fma(vec4(a[i / 4u][i % 4u]), b[q], acc[i][q]);
    }
    barrier();
  }
  gemm_store_tile(m0 + tm * kThreadM, n0 + tn * kThreadN, acc);
}

#endif

// The tile of this workgroup (the linear group index over tiles_m x tiles_n); false past the last.
bool gemm_tile_origin(out uint m0, out uint n0) {
  uint g = evf_linear_group(), tiles_m = (pc.gemm_m + kTileM - 1u) / kTileM;
  m0 = (g / pc.tiles_n) * kTileM;
  n0 = (g % pc.tiles_n) * kTileN;
  return g < tiles_m * pc.tiles_n;
}
