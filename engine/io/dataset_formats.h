// The dataset readers, one file per layout (io/dataset_<layout>.cpp), and what they share.
// Internal to io/: load_dataset (io/dataset.h) picks the reader.
#pragma once
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/dataset.h"
#include "io/llff.h"

namespace evflow::io::detail {

Dataset load_evflow(const std::filesystem::path& dir);
Dataset load_e3nerf(const std::filesystem::path& dir, const LoadOptions& opt);
Dataset load_ebad(const std::filesystem::path& dir, const LoadOptions& opt);
Dataset load_llff_sharp(const std::filesystem::path& dir, const LoadOptions& opt);
Dataset load_nerf_synthetic(const std::filesystem::path& dir);
Dataset load_recording(const std::filesystem::path& dir);

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what);
bool is_image_file(const std::filesystem::path& p);
// Regular, non-hidden files of `dir` that `keep` accepts; numeric stems sort as numbers.
std::vector<std::filesystem::path> list_files(const std::filesystem::path& dir,
                                              bool (*keep)(const std::filesystem::path&));
void require_file(const std::filesystem::path& p, const std::string& what);
// Image read + size check (w = 0: any size).
Image load_view_image(const std::filesystem::path& p, uint32_t w, uint32_t h);
// Fits the LLFF camera's intrinsics to the actual image size (LLFF files may store the
// full-resolution h, w, f of images that were downsampled).
void fit_camera_to_image(Camera& cam, uint32_t w, uint32_t h, const std::filesystem::path& poses, size_t row,
                         const std::filesystem::path& image);
void set_bounds(Dataset& ds, const PosesBounds& pb);
// The JSON document in `p`, failing with `p` when it cannot be opened or parsed.
nlohmann::json read_json_file(const std::filesystem::path& p);
// j[key], failing with `file` and `where` when missing.
const nlohmann::json& get(const nlohmann::json& j, const char* key, const std::filesystem::path& file,
                          const std::string& where);

}  // namespace evflow::io::detail
