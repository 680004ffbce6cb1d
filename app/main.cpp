// evflow: the command-line program. `evflow --help` lists the subcommands.
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <stdexcept>

#include "cli.h"

namespace evflow::app {

std::map<std::string, CommandInfo>& commands() {
  static std::map<std::string, CommandInfo> m;
  return m;
}

// An option given twice would have its second value taken for an unknown option: say so instead.
static void reject_repeat(const Args& args, const std::string& name) {
  for (const auto& a : args)
    if (a == name || a.rfind(name + "=", 0) == 0) throw std::invalid_argument(name + " is given twice");
}

bool ArgParser::flag(const std::string& name) {
  for (size_t i = 0; i < args.size(); ++i)
    if (args[i] == name) {
      args.erase(args.begin() + i);
      reject_repeat(args, name);
      return true;
    }
  return false;
}

std::string ArgParser::value(const std::string& name, const std::string& def) {
  for (size_t i = 0; i < args.size(); ++i) {
    std::string v;
    if (args[i] == name) {
      if (i + 1 >= args.size()) throw std::invalid_argument(name + " needs a value");
      v = args[i + 1];
      args.erase(args.begin() + i, args.begin() + i + 2);
    } else if (args[i].rfind(name + "=", 0) == 0) {
      v = args[i].substr(name.size() + 1);
      args.erase(args.begin() + i);
    } else {
      continue;
    }
    // An empty value (an unset shell variable, say) must not read as the option left out.
    if (v.empty()) throw std::invalid_argument(name + " needs a value, and the one given is empty");
    reject_repeat(args, name);
    return v;
  }
  return def;
}

long long ArgParser::integer(const std::string& name, long long def) {
  std::string v = value(name);
  if (v.empty()) return def;
  try {
    size_t pos;
    long long r = std::stoll(v, &pos);
    if (pos != v.size()) throw 1;
    return r;
  } catch (...) { throw std::invalid_argument(name + " expects an integer, got '" + v + "'"); }
}

long long ArgParser::integer(const std::string& name, long long def, long long lo, long long hi) {
  const long long r = integer(name, def);
  if (r < lo || r > hi)
    throw std::invalid_argument(name + " must be " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                                std::to_string(r));
  return r;
}

ImageSize ArgParser::image_size(ImageSize def, long long min_side) {
  return {uint32_t(integer("--width", def.width, min_side, kMaxImageSide)),
          uint32_t(integer("--height", def.height, min_side, kMaxImageSide))};
}

double ArgParser::number(const std::string& name, double def) {
  std::string v = value(name);
  if (v.empty()) return def;
  try {
    size_t pos;
    double r = std::stod(v, &pos);
    if (pos != v.size() || !std::isfinite(r)) throw 1;
    return r;
  } catch (...) { throw std::invalid_argument(name + " expects a finite number, got '" + v + "'"); }
}

std::vector<std::string> ArgParser::positional() const {
  std::vector<std::string> out;
  for (auto& a : args)
    if (a.rfind("--", 0) != 0) out.push_back(a);
  return out;
}

void ArgParser::reject_unknown() const {
  for (auto& a : args)
    if (a.rfind("--", 0) == 0) throw std::invalid_argument("unknown option " + a);
}

gpu::ContextOptions context_options(ArgParser& p) {
  gpu::ContextOptions o = gpu::ContextOptions::from_env();
  std::string dev = p.value("--device");
  if (!dev.empty()) o.device = dev;
  return o;
}

}  // namespace evflow::app

static void usage() {
  std::printf(
      "evflow — sharp 3D Gaussian splats from motion-blurred images and events\n\n"
      "usage: evflow <command> [options]   (evflow <command> --help for its options)\n\ncommands:\n");
  for (auto& [name, info] : evflow::app::commands()) std::printf("  %-10s %s\n", name.c_str(), info.summary.c_str());
}

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress lines appear as they happen in logs and pipes
  // Past a file-size limit (ulimit -f) a write fails with a clear error instead of killing us.
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage();
    return argc < 2 ? 2 : 0;
  }
  auto& cmds = evflow::app::commands();
  auto it = cmds.find(argv[1]);
  if (it == cmds.end()) {
    std::fprintf(stderr, "evflow: unknown command '%s'\n\n", argv[1]);
    usage();
    return 2;
  }
  try {
    return it->second.run(evflow::app::Args(argv + 2, argv + argc));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "evflow %s: error: %s\n", argv[1], e.what());
    return 1;
  }
}
