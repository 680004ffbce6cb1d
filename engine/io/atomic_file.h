// Atomic file writes: write into a temporary file next to the target, then rename it over the
// target, so a reader never sees a half-written file and a failed write leaves the old file alone.
#pragma once
#include <filesystem>
#include <fstream>
#include <functional>

namespace evflow::io {

// Calls `write(tmp)`, where `tmp` is a fresh path in the target's folder with the same extension
// (so extension-sniffing writers such as OpenImageIO pick the right format), then renames `tmp`
// onto `target`. Creates the target's parent folders. If `write` throws, or leaves no file at
// `tmp`, the temporary is removed, the target is untouched and the error propagates
// (std::runtime_error naming the target for a missing temporary or a failed rename).
// The temporary is named ".<stem>.tmp<pid>-<n><extension>".
void write_file_atomic(const std::filesystem::path& target,
                       const std::function<void(const std::filesystem::path& tmp)>& write);

// The same for a whole folder: `write(stage)` fills a fresh sibling folder ".<name>.tmp<pid>-<n>",
// which then replaces `target` (the old folder is renamed aside, the new one into place, the old
// one removed). If `write` throws, the stage is removed and `target` is untouched. An existing
// `target` must be empty or hold `marker` (e.g. dataset.json), so that no other folder is replaced.
void write_folder_atomic(const std::filesystem::path& target, const std::string& marker,
                         const std::function<void(const std::filesystem::path& stage)>& write);

// Closes `f`, flushing what it buffered, and throws std::runtime_error naming `target` and the
// system's reason (a full disk, a file-size limit) when opening, writing or flushing failed.
void close_or_throw(std::ofstream& f, const std::filesystem::path& target);

// Removes the temporaries that write_file_atomic(target) left behind when its process was
// killed mid-write (those of processes that no longer run); returns how many it removed.
int remove_stale_temporaries(const std::filesystem::path& target);

}  // namespace evflow::io
