// evflow view RUN|file.ply|file.glb [--width 800] [--height 600] [--frames N] [--screenshot out.png]
//             [--fps-cap 30] [--vsync] [--device D] [--resize-to WxH]
#include <cstdio>

#include "cli.h"
#include "io/gltf_splats.h"
#include "io/ply_splats.h"
#include "run_files.h"
#include "viewer/viewer.h"

namespace evflow::app {

static int run_view(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf(
        "usage: evflow view RUN|file.ply|file.glb [--width 800] [--height 600] [--fps-cap 30] [--vsync]\n"
        "                   [--frames N] [--screenshot out.png] [--device D]\n"
        "  A window showing the splats from an orbit camera (docs/viewer.md): left-drag rotates about\n"
        "  the cloud's centre, the wheel zooms, W/A/S/D/Q/E fly, Esc quits. --frames N exits after N\n"
        "  presented frames; --screenshot writes the last one as PNG. Exits 3 if the validation layer\n"
        "  (EVF_VALIDATION=1) reported anything. --resize-to WxH (testing) resizes the window after two\n"
        "  frames; the run then ends only once a frame of the new size was presented.\n");
    return 0;
  }
  viewer::ViewerOptions o;
  const ImageSize size = p.image_size({800, 600}, 16);
  o.width = size.width;
  o.height = size.height;
  o.frames = int(p.integer("--frames", 0, 0, 100000000));
  o.screenshot = p.value("--screenshot");
  o.fps_cap = p.number("--fps-cap", 30.0);
  o.vsync = p.flag("--vsync");
  std::string resize = p.value("--resize-to");
  if (!resize.empty()) {
    unsigned rw = 0, rh = 0;
    if (std::sscanf(resize.c_str(), "%ux%u", &rw, &rh) != 2 || rw < 16 || rh < 16)
      throw std::invalid_argument("--resize-to WxH, e.g. 200x150");
    o.resize_width = rw;
    o.resize_height = rh;
  }
  o.context = context_options(p);
  p.reject_unknown();
  auto pos = p.positional();
  if (pos.size() != 1) throw std::invalid_argument("usage: evflow view RUN|file.ply|file.glb [options] (--help)");
  if (!o.screenshot.empty() && o.frames <= 0) throw std::invalid_argument("--screenshot needs --frames N");
  std::filesystem::path src = pos[0];
  const GaussianCloud cloud = load_splats(src);
  o.title = "evflow view " + src.filename().string();
  return viewer::run_viewer(cloud, o);
}

static Command reg("view", "open a window showing splats (orbit camera; --frames/--screenshot for tests)", run_view);

}  // namespace evflow::app
