// Gaussian splats as Inria-layout PLY (the .ply that the 3DGS reference code writes and most
// splat viewers read). Field mapping and tolerances: docs/export.md.
#pragma once
#include <filesystem>

#include "cloud/gaussian_cloud.h"

namespace evflow::io {

// Writes `cloud` as binary little-endian float32 PLY, one `vertex` element with the properties
//   x y z nx ny nz f_dc_0..2 f_rest_0..(3(K-1)-1) opacity scale_0..2 rot_0..3
// holding the pre-activation values unchanged (opacity logit, log scale, quaternion w x y z;
// normals are zero). f_rest is channel-major: f_rest[c * (K-1) + (k-1)] = sh[n][k][c].
// Atomic (io/atomic_file.h). Throws std::invalid_argument when the cloud fails validate(), and
// std::runtime_error naming the file when it cannot be written.
void write_ply(const std::filesystem::path& path, const GaussianCloud& cloud);

// Reads an Inria-layout PLY: properties in any order, float or double (other vertex properties,
// e.g. nx or red, of any type are ignored), binary little/big endian or ascii, other elements
// skipped. The SH degree follows from the number of f_rest_* properties (0, 9, 24 or 45).
// Values are taken as stored (pre-activation; the quaternion is not normalised).
// Throws std::runtime_error naming the file and the problem for anything malformed: bad header,
// missing or duplicate properties, wrong f_rest count, truncated data, NaN or infinite values.
GaussianCloud read_ply(const std::filesystem::path& path);

}  // namespace evflow::io
