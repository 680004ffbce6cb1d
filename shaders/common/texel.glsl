// Reads through texel buffers (uniform texel buffers: samplerBuffer RGBA32F, usamplerBuffer
// R32UI; engine/gpu/kernel.h). On lavapipe a texel fetch at a different index in each SIMD lane
// is straight-line code, where a storage-buffer load is a loop over the lanes. A buffer is a whole
// number of 16 bytes (gpu/buffer.h), so an RGBA32F view covers a float plane's last elements.

#ifndef EVF_TEXEL_GLSL
#define EVF_TEXEL_GLSL
// Element i of a float array viewed as RGBA32F texels.
float evf_texel_float(samplerBuffer b, uint i) { return texelFetch(b, int(i >> 2u))[i & 3u]; }
// Elements 4i .. 4i+3 of a uint array viewed as R32UI texels.
uvec4 evf_texel_uvec4(usamplerBuffer b, uint i) {
  int t = int(4u * i);
  return uvec4(texelFetch(b, t).x, texelFetch(b, t + 1).x, texelFetch(b, t + 2).x, texelFetch(b, t + 3).x);
}
#endif
