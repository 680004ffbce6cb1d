// Subcommand registry: each app/cmd_*.cpp registers one subcommand with a static Command.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace evflow::app {

using Args = std::vector<std::string>;

struct CommandInfo {
  std::string summary;
  std::function<int(const Args&)> run;
};

std::map<std::string, CommandInfo>& commands();

struct Command {
  Command(const std::string& name, const std::string& summary, std::function<int(const Args&)> run) {
    commands()[name] = {summary, std::move(run)};
  }
};

// Small argument helpers: "--key value" and "--flag". An option given twice, or given an empty
// value, is refused; numbers must be finite.
// "a, b, c" from {a, b, c} with sep ", ".
inline std::string join(const std::vector<std::string>& items, const std::string& sep) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : sep) + i;
  return s;
}

// The largest image width or height any command takes (a bound, not a limit of the renderer's).
inline constexpr long long kMaxImageSide = 16384;

// An image's width and height in pixels.
struct ImageSize {
  uint32_t width, height;
};

struct ArgParser {
  explicit ArgParser(const Args& a) : args(a) {}
  Args args;
  bool flag(const std::string& name);
  std::string value(const std::string& name, const std::string& def = "");
  long long integer(const std::string& name, long long def);
  long long integer(const std::string& name, long long def, long long lo, long long hi);  // refuses outside [lo, hi]
  double number(const std::string& name, double def);
  // --width and --height, each refused outside [min_side, kMaxImageSide].
  ImageSize image_size(ImageSize def, long long min_side = 1);
  std::vector<std::string> positional() const;  // what is left after flags and values were taken
  void reject_unknown() const;                  // throws on any leftover --option
};

}  // namespace evflow::app

#include "gpu/context.h"

namespace evflow::app {

// Context options from the environment (EVF_DEVICE, EVF_VALIDATION, EVF_POISON) and --device.
gpu::ContextOptions context_options(ArgParser& p);

}  // namespace evflow::app
