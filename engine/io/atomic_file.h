// Atomic file writes: write into a temporary file next to the target, then rename it over the
// target, so a reader never sees a half-written file and a failed write leaves the old file alone.
#pragma once
#include <filesystem>
#include <functional>

namespace evflow::io {

// Calls `write(tmp)`, where `tmp` is a fresh path in the target's folder with the same extension
// (so extension-sniffing writers such as OpenImageIO pick the right format), then renames `tmp`
// onto `target`. Creates the target's parent folders. If `write` throws, or leaves no file at
// `tmp`, the temporary is removed, the target is untouched and the error propagates
// (std::runtime_error naming the target for a missing temporary or a failed rename).
void write_file_atomic(const std::filesystem::path& target,
                       const std::function<void(const std::filesystem::path& tmp)>& write);

}  // namespace evflow::io
