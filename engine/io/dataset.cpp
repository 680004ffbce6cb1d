#include "io/dataset.h"

#include "io/dataset_formats.h"

namespace evflow::io {

namespace fs = std::filesystem;

namespace {

// The layouts load_dataset knows, in the order it tries them: the first whose marker files
// `dir` holds is read.
struct Format {
  const char* name;
  bool (*detect)(const fs::path& dir);
  Dataset (*read)(const fs::path& dir, const LoadOptions& opt);
};

const Format kFormats[] = {
    {"evflow",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::exists(d / "dataset.json", ec);
     },
     [](const fs::path& d, const LoadOptions&) { return detail::load_evflow(d); }},
    {"recording",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::exists(d / "recording.json", ec);
     },
     [](const fs::path& d, const LoadOptions&) { return detail::load_recording(d); }},
    {"ebad",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::exists(d / "events.npy", ec);
     },
     detail::load_ebad},
    {"e3nerf",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::is_directory(d / "events", ec) && fs::is_directory(d / "gt", ec);
     },
     detail::load_e3nerf},
    {"nerf_synthetic",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::exists(d / "transforms_train.json", ec);
     },
     [](const fs::path& d, const LoadOptions&) { return detail::load_nerf_synthetic(d); }},
    {"llff",
     [](const fs::path& d) {
       std::error_code ec;
       return fs::exists(d / "poses_bounds.npy", ec) && fs::is_directory(d / "images", ec);
     },
     detail::load_llff_sharp},
};

}  // namespace

Dataset load_dataset(const fs::path& dir, const LoadOptions& opt) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) detail::fail(dir, "is a file, and a dataset is a folder");
  if (!fs::is_directory(dir, ec)) detail::fail(dir, "dataset folder is missing");
  for (const Format& f : kFormats)
    if (f.detect(dir)) return f.read(dir, opt);
  detail::fail(dir,
               "unrecognised dataset layout: expected dataset.json (EvFlow), recording.json (a recording without "
               "poses), events.npy (EBAD-NeRF), events/ + gt/ (E3NeRF), "
               "transforms_train.json (NeRF-synthetic) or images/ + poses_bounds.npy (LLFF)");
}

}  // namespace evflow::io
