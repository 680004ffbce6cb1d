// evflow export RUN|file.ply|file.glb [--gltf out.glb] [--ply out.ply]
#include <cstdio>

#include "cli.h"
#include "io/gltf_splats.h"
#include "io/ply_splats.h"
#include "run_files.h"

namespace evflow::app {

static int run_export(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf(
        "usage: evflow export RUN|file.ply|file.glb [--gltf out.glb|out.gltf] [--ply out.ply] [--linear-color]\n"
        "  glTF 2.0 with KHR_gaussian_splatting, or the Inria PLY layout (docs/export.md).\n");
    return 0;
  }
  std::string gltf = p.value("--gltf"), ply = p.value("--ply");
  bool linear = p.flag("--linear-color");
  p.reject_unknown();
  auto pos = p.positional();
  if (pos.size() != 1 || (gltf.empty() && ply.empty()))
    throw std::invalid_argument("usage: evflow export SOURCE --gltf F and/or --ply F");
  std::filesystem::path src = pos[0];
  GaussianCloud cloud;
  if (std::filesystem::is_directory(src))
    cloud = RunFolder::open(src).checkpoint.cloud;
  else if (src.extension() == ".ply")
    cloud = io::read_ply(src);
  else
    cloud = io::read_gltf_splats(src);
  if (!gltf.empty()) {
    io::GltfExportOptions o;
    if (linear) o.color_space = io::GltfColorSpace::lin_rec709_display;
    io::write_gltf_splats(gltf, cloud, o);
    std::printf("wrote %s (%zu Gaussians, SH degree %d)\n", gltf.c_str(), cloud.size(), cloud.sh_degree);
  }
  if (!ply.empty()) {
    io::write_ply(ply, cloud);
    std::printf("wrote %s (%zu Gaussians, SH degree %d)\n", ply.c_str(), cloud.size(), cloud.sh_degree);
  }
  return 0;
}

static Command reg("export", "write trained splats as glTF (KHR_gaussian_splatting) or PLY", run_export);

}  // namespace evflow::app
