// evflow devices: list the Vulkan devices and what EvFlow would use.
#include <cstdio>

#include "cli.h"
#include "gpu/context.h"

namespace evflow::app {

static int run_devices(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) {
    std::printf("usage: evflow devices [--device N|name]\n");
    return 0;
  }
  gpu::ContextOptions o = context_options(p);
  p.reject_unknown();
  for (auto& d : gpu::Context::list_devices()) std::printf("%s\n", d.c_str());
  gpu::Context ctx(o);
  auto& c = ctx.caps();
  std::printf(
      "selected: %s\n  subgroup size %u, shared memory %u B, max storage binding %llu MiB,\n"
      "  workgroups per dimension %u, float atomics (shared) %s, unified memory %s\n",
      c.name.c_str(), c.subgroup_size, c.max_shared_memory,
      static_cast<unsigned long long>(c.max_storage_buffer_range >> 20), c.max_workgroup_count[0],
      c.shared_float_atomic_add ? "yes" : "no (compare-and-swap)", c.unified_memory ? "yes" : "no");
  return 0;
}

static Command reg("devices", "list Vulkan devices and the limits EvFlow reads from them", run_devices);

}  // namespace evflow::app
