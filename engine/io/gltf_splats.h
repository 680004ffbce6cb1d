// Gaussian splats as glTF 2.0 with the KHR_gaussian_splatting extension (Release Candidate).
// Field mapping, conversions and round-trip tolerances: docs/export.md.
#pragma once
#include <filesystem>

#include "cloud/gaussian_cloud.h"

namespace evflow::io {

// The extension's `colorSpace`: what the SH colours (sum + 0.5) mean. EvFlow trains on sRGB
// images, so its splats are srgb_rec709_display unless trained on linear data.
enum class GltfColorSpace { srgb_rec709_display, lin_rec709_display };

struct GltfExportOptions {
  GltfColorSpace color_space = GltfColorSpace::srgb_rec709_display;
  // Also write COLOR_0 (float VEC4, linear as glTF requires): the diffuse colour
  // clamp(0.28209479177387814 * dc + 0.5, 0, 1), sRGB-decoded when color_space is sRGB, and
  // alpha = opacity, so that viewers without the extension show a coloured point cloud.
  bool color_fallback = true;
};

// Writes one mesh with one POINTS primitive carrying KHR_gaussian_splatting
// ({kernel: "ellipse", colorSpace}) and the attributes POSITION (with min/max),
// KHR_gaussian_splatting:ROTATION (unit quaternion x y z w), :SCALE (exp(log_scale)),
// :OPACITY (sigmoid(logit)), :SH_DEGREE_l_COEF_n for l = 0..degree, n = 0..2l (m = n - l), all
// float32, and optionally COLOR_0. `.glb` gives binary glTF; `.gltf` gives JSON with the buffer
// embedded as a base64 data URI; any other extension is an error. Atomic (io/atomic_file.h).
// Throws std::invalid_argument for a cloud that fails validate(), is empty, or whose values do
// not fit the format (exp(log_scale) overflowing float), std::runtime_error for I/O failures.
void write_gltf_splats(const std::filesystem::path& path, const GaussianCloud& cloud,
                       const GltfExportOptions& options = {});

// Reads every mesh primitive carrying KHR_gaussian_splatting from a .glb or .gltf (detected from
// the content; buffers: GLB BIN chunk, base64 data URIs or files next to the .gltf), concatenated
// in mesh/primitive order, back into pre-activation parameters: log(scale) (scale 0 -> log of
// 1e-30), logit(clamp(opacity, 1e-6, 1 - 1e-6)), quaternion w x y z as stored. Accepts the
// component types the extension allows (normalised integer rotation/opacity, integer scale),
// interleaved buffer views and primitives of different SH degrees (missing degrees read as zero).
// Node transforms are not applied. If `color_space` is given, it receives the file's colorSpace.
// Throws std::runtime_error naming the file for anything malformed or unsupported (not glTF,
// no splat primitive, missing attributes, out-of-range indices, truncated buffers, NaN values,
// negative scale, opacity outside [0, 1], kernel other than "ellipse", required extensions).
GaussianCloud read_gltf_splats(const std::filesystem::path& path, GltfColorSpace* color_space = nullptr);

}  // namespace evflow::io
